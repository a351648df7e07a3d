#pragma once
// What becomes of a socket accepted on the subscriber port: it moves to the publish thread with
// the fewest subscribers (PublishThreads::place), admission decides its place, it joins the
// first subject's hub until its Hello names another, and its session starts on its own thread.
// Accepting straight onto a publish context would leave the waiting accept, and a socket of a
// publish context, in the accepting io_context's queue, which outlives the publish threads: the
// socket is taken over by descriptor instead. Without publish threads it stays where it was
// accepted.

#include <memory>

#include "server/asio.h"

namespace skinstream::server {

class PublishThreads;
class SubscriberAdmission;
class SubscriberHub;

// On the accepting thread (`accepting` is the socket's context). A socket whose peer is gone,
// or that cannot be moved (said in one line), is closed.
void hand_off_tcp_subscriber(tcp::socket socket, asio::io_context& accepting, PublishThreads& publish,
                             SubscriberHub& first_hub, const std::shared_ptr<SubscriberAdmission>& admission);

}  // namespace skinstream::server
