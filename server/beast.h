#pragma once
// Boost.Beast (HTTP and WebSocket) for the daemon's HTTP port; see server/asio.h.
#include "server/asio.h"

#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

namespace skinstream::server {
namespace beast = boost::beast;
namespace http = boost::beast::http;
namespace websocket = boost::beast::websocket;
}  // namespace skinstream::server
