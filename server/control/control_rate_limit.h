#pragma once
// Wrong tokens cost a peer time: after max_refusals wrong tokens from one address within
// `window`, every control request from it is refused (429) for `block`, so the token cannot be
// guessed at the speed of the network. The table of addresses is bounded (max_addresses): once
// it is full of live entries, every address not in it shares one entry, so a flood from many
// addresses is blocked together and cannot grow the daemon's memory. Any thread.

#include <chrono>
#include <mutex>
#include <string>
#include <unordered_map>

namespace skinstream::server {

struct ControlRateLimitOptions {
  int max_refusals = 5;  // wrong tokens from one address within `window` ...
  std::chrono::milliseconds window{10'000};
  std::chrono::milliseconds block{60'000};  // ... then all its control requests are refused this long
  size_t max_addresses = 1024;              // addresses tracked at once
};

class ControlRateLimit {
 public:
  using Clock = std::chrono::steady_clock;

  explicit ControlRateLimit(ControlRateLimitOptions options = {}) : options_(options) {}

  // How much longer `address` is refused (zero: it is not).
  std::chrono::milliseconds blocked_for(const std::string& address, Clock::time_point now);
  // Counts a wrong token from `address`; true when this one starts its block.
  bool count_refusal(const std::string& address, Clock::time_point now);

  size_t tracked_addresses() const;
  const ControlRateLimitOptions& options() const { return options_; }

 private:
  struct Entry {
    Clock::time_point window_start{};
    int refusals = 0;
    Clock::time_point blocked_until{};
  };
  // The address's entry, made when it has none (the shared one when the table is full).
  Entry& entry_for(const std::string& address, Clock::time_point now);
  const Entry* find(const std::string& address) const;
  bool expired(const Entry& entry, Clock::time_point now) const;

  ControlRateLimitOptions options_;
  mutable std::mutex mutex_;
  std::unordered_map<std::string, Entry> entries_;
  Entry shared_;  // every address the full table has no room for
};

}  // namespace skinstream::server
