#pragma once
// The one way skinstream includes Boost.Asio and Boost.Beast. Both are compiled once, in
// server/asio_impl.cpp (BOOST_ASIO_SEPARATE_COMPILATION / BOOST_BEAST_SEPARATE_COMPILATION are
// set on the skinstream_server target), so the other translation units only parse the headers.
#include <utility>  // Boost 1.74 Asio uses std::exchange without including it

#include <boost/asio.hpp>

namespace skinstream::server {
namespace asio = boost::asio;
using tcp = boost::asio::ip::tcp;
using udp = boost::asio::ip::udp;
}  // namespace skinstream::server
