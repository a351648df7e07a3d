#include "server/control/control_rate_limit.h"

namespace skinstream::server {

bool ControlRateLimit::expired(const Entry& entry, Clock::time_point now) const {
  return entry.blocked_until <= now && now - entry.window_start >= options_.window;
}

const ControlRateLimit::Entry* ControlRateLimit::find(const std::string& address) const {
  const auto it = entries_.find(address);
  if (it != entries_.end()) return &it->second;
  return entries_.size() >= options_.max_addresses ? &shared_ : nullptr;
}

ControlRateLimit::Entry& ControlRateLimit::entry_for(const std::string& address, Clock::time_point now) {
  if (const auto it = entries_.find(address); it != entries_.end()) return it->second;
  if (entries_.size() >= options_.max_addresses)
    std::erase_if(entries_, [&](const auto& item) { return expired(item.second, now); });
  if (entries_.size() >= options_.max_addresses) return shared_;
  return entries_[address];
}

std::chrono::milliseconds ControlRateLimit::blocked_for(const std::string& address, Clock::time_point now) {
  std::lock_guard lock(mutex_);
  const Entry* entry = find(address);
  if (!entry || entry->blocked_until <= now) return std::chrono::milliseconds(0);
  return std::chrono::ceil<std::chrono::milliseconds>(entry->blocked_until - now);
}

bool ControlRateLimit::count_refusal(const std::string& address, Clock::time_point now) {
  std::lock_guard lock(mutex_);
  Entry& entry = entry_for(address, now);
  if (now - entry.window_start >= options_.window) {
    entry.window_start = now;
    entry.refusals = 0;
  }
  if (++entry.refusals < options_.max_refusals) return false;
  entry.refusals = 0;
  entry.window_start = now;
  const bool starts = entry.blocked_until <= now;
  entry.blocked_until = now + options_.block;
  return starts;
}

size_t ControlRateLimit::tracked_addresses() const {
  std::lock_guard lock(mutex_);
  return entries_.size();
}

}  // namespace skinstream::server
