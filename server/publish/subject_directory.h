#pragma once
// The daemon's subjects' hubs by name, for a subscriber that names the subject it wants in its
// Hello (version 2): the empty name is the first subject; a name the daemon does not serve finds
// nothing (the subscriber is refused, and told which names there are). Subjects come and go at
// run time (the io thread adds and removes them; the subscribers' threads look them up).

#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace skinstream::server {

class SubscriberHub;

class SubjectDirectory {
 public:
  void add(std::string name, SubscriberHub& hub) {
    std::lock_guard lock(mutex_);
    entries_.emplace_back(std::move(name), &hub);
  }
  void remove(std::string_view name) {
    std::lock_guard lock(mutex_);
    std::erase_if(entries_, [&](const auto& entry) { return entry.first == name; });
  }

  SubscriberHub* find(std::string_view name) const {
    std::lock_guard lock(mutex_);
    if (name.empty()) return entries_.empty() ? nullptr : entries_.front().second;
    for (const auto& [own, hub] : entries_)
      if (own == name) return hub;
    return nullptr;
  }

  // "\"Actor1\", \"Actor2\"": what a refusal says the daemon serves.
  std::string names() const {
    std::lock_guard lock(mutex_);
    std::string out;
    for (const auto& entry : entries_) out += (out.empty() ? "\"" : ", \"") + entry.first + "\"";
    return out;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<std::pair<std::string, SubscriberHub*>> entries_;
};

}  // namespace skinstream::server
