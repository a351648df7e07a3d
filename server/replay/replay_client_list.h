#pragma once
// The clients a replay server serves (replay_client.h). A closed client is forgotten after the
// handler that closed it has returned: it may be in the middle of its own handler.
//
// Threading: every member runs on the io_context's thread.

#include <algorithm>
#include <memory>
#include <vector>

#include "server/asio.h"
#include "server/replay/replay_client.h"

namespace skinstream::server {

template <typename Client>
class ReplayClientList {
 public:
  explicit ReplayClientList(asio::io_context& io) : io_(io) {}

  void add(std::shared_ptr<Client> client) { clients_->push_back(std::move(client)); }
  void forget(const ReplayClient* client) {
    // The list itself is kept by the posted handler: the server may be gone by then.
    asio::post(io_, [clients = clients_, client] {
      std::erase_if(*clients, [client](const auto& c) { return c.get() == client; });
    });
  }
  // A copy to go through: a client served may close, and be forgotten, on the way.
  std::vector<std::shared_ptr<Client>> snapshot() const { return *clients_; }
  void close_all() {
    for (auto& client : snapshot()) client->close();
    clients_->clear();
  }
  bool all_idle() const {
    return std::all_of(clients_->begin(), clients_->end(), [](const auto& c) { return c->idle(); });
  }
  size_t size() const { return clients_->size(); }

 private:
  asio::io_context& io_;
  std::shared_ptr<std::vector<std::shared_ptr<Client>>> clients_ =
      std::make_shared<std::vector<std::shared_ptr<Client>>>();
};

}  // namespace skinstream::server
