#pragma once
// How an estimate has lately done against what it claimed: forgetting sums of its squared miss
// and of the variance it claimed (per coordinate), each check weighed by the time it stands for.
// Their ratio is a calibration learned online: above one, the estimate claimed too much.
// Used by the regions' prequential calibration (region_online_statistics.h) and the one-ring and
// eq. 2 checks of the gap filler (ring_calibration.h).

namespace skinstream {

struct RecentMiss {
  double squared_miss = 0.0;
  double claimed = 0.0;

  // `forget`: what the sums so far still count for; `weight`: what this check counts for.
  void add(double forget, double weight, double miss, double claim) {
    squared_miss = forget * squared_miss + weight * miss;
    claimed = forget * claimed + weight * claim;
  }
  bool any() const { return claimed > 0.0; }
  double ratio() const { return squared_miss / claimed; }  // only when any()
};

}  // namespace skinstream
