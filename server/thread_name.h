#pragma once
// Names the calling thread, so `top -H`, `ps -L` and perf show which of the daemon's threads
// does what (io, pipeline, deform-N, publish-N) instead of "skinstreamd" on every line. A
// thread started by a named one inherits its name: Asio's resolver thread shows as a second "io".

#include <string>
#include <string_view>

namespace skinstream::server {

// Linux keeps at most 15 characters; longer names are cut there. Returns false when the OS
// refuses (the thread keeps its old name; nothing else depends on it).
bool name_this_thread(std::string_view name);
// The calling thread's name as the OS has it.
std::string this_thread_name();

}  // namespace skinstream::server
