#pragma once
// Names already reported, so each is reported once, with a cap on how many are remembered: a
// source that invents new subject or label names every frame must not make the daemon's memory
// (or its log) grow without bound. Past the cap, new names are only counted.

#include <cstddef>
#include <string>
#include <string_view>
#include <unordered_set>

namespace skinstream::server {

class BoundedNameSet {
 public:
  explicit BoundedNameSet(size_t capacity) : capacity_(capacity) {}

  enum class Insert { New, Known, Full };
  // New: remembered now (report it); Known: reported before; Full: not remembered (count it).
  Insert insert(std::string_view name) {
    if (names_.count(std::string(name)) > 0) return Insert::Known;
    if (names_.size() >= capacity_) return Insert::Full;
    names_.emplace(name);
    return Insert::New;
  }
  size_t size() const { return names_.size(); }
  size_t capacity() const { return capacity_; }

 private:
  size_t capacity_;
  std::unordered_set<std::string> names_;
};

}  // namespace skinstream::server
