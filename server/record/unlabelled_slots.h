#pragma once
// Which of a received take's unlabelled channels ("*1".."*N") each unlabelled point goes into,
// so that the take replays as it came: a point whose trajectory id continues from the previous
// frame stays in its channel, and a new trajectory (or a point without an id) only takes a
// channel that was empty in the previous frame. Read back, a channel is one trajectory fragment
// (its index the id), and the gap filler sees the same fragments begin and end as it did live:
// it keeps a fragment only while its id is present frame after frame.
//
// Used on the take writer's thread; allocates only while ids it has not seen are being mapped.

#include <span>
#include <unordered_map>
#include <vector>

namespace skinstream::server {

class UnlabelledSlots {
 public:
  explicit UnlabelledSlots(int slots);

  // The points of one frame, by their source trajectory ids (-1: none). Sets out_slot[j] to the
  // channel of point j, or -1 when every channel that point could take is in use (not kept).
  // Returns how many were kept.
  int assign(std::span<const int> ids, std::span<int> out_slot);

 private:
  static constexpr int kNone = -2;
  std::vector<int> slot_id_;  // the id each channel last held (kNone: never)
  std::vector<char> used_previous_, used_now_;
  std::unordered_map<int, int> slot_of_id_;
};

}  // namespace skinstream::server
