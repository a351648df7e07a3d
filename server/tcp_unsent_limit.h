#pragma once
// How many bytes a TCP socket may hold that the network has not taken yet (Linux
// TCP_NOTSENT_LOWAT): a send beyond it takes no more and the socket is not writable again until
// the unsent bytes fall below it. A reader that keeps up leaves nothing unsent (loopback or a
// LAN takes the data as fast as it comes), so its throughput is unchanged; a reader that stopped
// costs at most this much instead of the 2.6-4 MB Linux gives a socket's send buffer on
// loopback (tcp_wmem), which the daemon would otherwise copy into the kernel per subscriber.

#include <string>

namespace skinstream::server {

// Returns an empty string on success, otherwise why not (the socket stays usable, unlimited).
std::string set_tcp_unsent_limit(int socket_handle, int bytes);
// The socket's limit in bytes, or -1 when it cannot be read.
int tcp_unsent_limit_of(int socket_handle);

}  // namespace skinstream::server
