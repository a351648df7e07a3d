#pragma once
// Text from a file or a peer, made fit for a one-line message: every byte outside printable
// ASCII (line breaks, terminal escapes, invalid UTF-8) becomes \xNN, and text longer than
// `max_bytes` is cut with a note of its length. Error messages and logs stay one readable line,
// and /health's JSON (which must be valid UTF-8) can carry them.

#include <cstddef>
#include <string>
#include <string_view>

namespace skinstream {

std::string printable_text(std::string_view text, size_t max_bytes = 256);

// printable_text() in single quotes, cut at 40 bytes: a name or token inside a message.
std::string quoted_text(std::string_view text);

}  // namespace skinstream
