#pragma once
// The clients a replay server serves (replay_client.h). A closed client is forgotten after the
// handler that closed it has returned: it may be in the middle of its own handler.
//
// Threading: every member runs on the io_context's thread.

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "server/asio.h"
#include "server/logging.h"
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

// The rule of the TCP replay servers for a new connection: beyond `max_clients` open at once it is
// refused (counted, said in a rate-limited line; the caller lets the socket close), else counted as
// accepted and open. `Stats` has the atomics clients_open, clients_refused and clients_accepted.
template <typename Stats>
bool admit_replay_client(Stats& stats, size_t max_clients, RateLimitedLog& log, const char* server) {
  if (static_cast<size_t>(stats.clients_open.load()) >= max_clients) {
    ++stats.clients_refused;
    log.warn(std::string(server) + "_too_many_clients",
             std::string(server) + " server: closing a connection beyond the " + std::to_string(max_clients) +
                 " clients served at once");
    return false;
  }
  ++stats.clients_accepted;
  ++stats.clients_open;
  return true;
}

}  // namespace skinstream::server
