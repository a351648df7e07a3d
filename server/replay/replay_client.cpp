#include "server/replay/replay_client.h"

#include <algorithm>

namespace skinstream::server {

ReplayClient::ReplayClient(tcp::socket socket, const ReplayClientContext& context)
    : socket_(std::move(socket)), context_(context) {}

void ReplayClient::enqueue(Packet packet, bool is_frame) {
  if (!open_) return;
  if (is_frame) {
    const auto waiting = queue_.begin() + (writing_ ? 1 : 0);
    const auto frame = [](const Outgoing& o) { return o.is_frame; };
    if (static_cast<size_t>(std::count_if(waiting, queue_.end(), frame)) >=
        std::max<size_t>(1, context_.max_queued_frames)) {
      queue_.erase(std::find_if(waiting, queue_.end(), frame));
      ++context_.frames_dropped;
    }
  }
  queue_.push_back({std::move(packet), is_frame});
  replies_waiting_ += is_frame ? 0 : 1;
  write();
}

void ReplayClient::write() {
  if (writing_ || queue_.empty() || !open_) return;
  writing_ = true;
  asio::async_write(socket_, asio::buffer(*queue_.front().packet),
                    [self = shared_from_this()](const boost::system::error_code& ec, size_t) {
                      self->on_written(ec);
                    });
}

void ReplayClient::on_written(const boost::system::error_code& ec) {
  writing_ = false;
  if (!open_) return;
  if (ec) return close();
  if (queue_.front().is_frame)
    ++context_.frame_packets_sent;
  else
    --replies_waiting_;
  queue_.pop_front();
  write();
  after_write();
}

void ReplayClient::reject(const std::string& reason) {
  ++context_.bad_clients;
  context_.log.warn(context_.bad_client_category,
                    context_.server_name + ": closing a client that sent malformed input: " + reason);
  close();
}

void ReplayClient::close() {
  if (!open_) return;
  open_ = false;
  boost::system::error_code ignored;
  socket_.shutdown(tcp::socket::shutdown_both, ignored);
  socket_.close(ignored);
  queue_.clear();
  replies_waiting_ = 0;
  --context_.clients_open;
  closed();
}

}  // namespace skinstream::server
