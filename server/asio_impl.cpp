// The compiled parts of Boost.Asio and Boost.Beast, once for the whole project (server/asio.h).
#include <utility>

#include <boost/asio/impl/src.hpp>
#include <boost/beast/src.hpp>
