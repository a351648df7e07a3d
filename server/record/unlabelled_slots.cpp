#include "server/record/unlabelled_slots.h"

#include <algorithm>

namespace skinstream::server {

UnlabelledSlots::UnlabelledSlots(int slots)
    : slot_id_(static_cast<size_t>(std::max(slots, 0)), kNone),
      used_previous_(slot_id_.size(), 0),
      used_now_(slot_id_.size(), 0) {}

int UnlabelledSlots::assign(std::span<const int> ids, std::span<int> out_slot) {
  used_previous_.swap(used_now_);
  std::fill(used_now_.begin(), used_now_.end(), 0);
  // Continuing trajectories first, so that a new one cannot take their channel.
  for (size_t j = 0; j < ids.size(); ++j) {
    out_slot[j] = -1;
    if (ids[j] < 0) continue;
    const auto known = slot_of_id_.find(ids[j]);
    if (known == slot_of_id_.end()) continue;
    const int slot = known->second;
    if (used_previous_[slot] && !used_now_[slot] && slot_id_[slot] == ids[j]) {
      out_slot[j] = slot;
      used_now_[slot] = 1;
    }
  }
  int kept = 0;
  size_t next_free = 0;
  for (size_t j = 0; j < ids.size(); ++j) {
    if (out_slot[j] >= 0) {
      ++kept;
      continue;
    }
    // The same id back after a gap keeps its channel when that channel rested a frame.
    int slot = -1;
    if (ids[j] >= 0) {
      const auto known = slot_of_id_.find(ids[j]);
      if (known != slot_of_id_.end() && slot_id_[known->second] == ids[j] && !used_previous_[known->second] &&
          !used_now_[known->second])
        slot = known->second;
    }
    while (slot < 0 && next_free < slot_id_.size()) {
      const size_t candidate = next_free++;
      if (!used_previous_[candidate] && !used_now_[candidate]) slot = static_cast<int>(candidate);
    }
    if (slot < 0) continue;  // more new trajectories than rested channels this frame
    if (slot_id_[slot] >= 0) {
      const auto old = slot_of_id_.find(slot_id_[slot]);
      if (old != slot_of_id_.end() && old->second == slot) slot_of_id_.erase(old);
    }
    slot_id_[slot] = ids[j];
    if (ids[j] >= 0) slot_of_id_[ids[j]] = slot;
    used_now_[slot] = 1;
    out_slot[j] = slot;
    ++kept;
  }
  return kept;
}

}  // namespace skinstream::server
