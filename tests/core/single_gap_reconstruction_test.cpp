#include "core/single_gap_reconstruction.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/offline/subject_builder.h"
#include "core/pca_fit.h"
#include "support/allocation_counter.h"
#include "support/synthetic_limb.h"

namespace skinstream {
namespace {

// Each ring member's neighbours in a pose off the model's mean (the reference moved by a few
// millimetres), in the marker's local frame.
std::vector<Vec3> moved_ring(const SubjectModel& model, int j) {
  std::vector<Vec3> local;
  for (int k = model.ring_offsets[j]; k < model.ring_offsets[j + 1]; ++k)
    local.push_back(model.ring_local_reference[k] +
                    Vec3(3.0 * std::sin(k), 2.0 * std::cos(k), 0.5 * (k % 5)));
  return local;
}

// The precomputed map is the regularised least squares of PcaFit with one member left out: the
// same reconstruction, the same miss, and PcaFit's predictive variance times the member's
// calibration.
TEST(SingleGapReconstruction, IsPcaFitWithOneMemberLeftOut) {
  const SubjectModel model = build_subject(test::make_limb_capture(), {});
  SingleGapReconstruction single_gaps(model);
  int tried = 0;
  for (int j = 0; j < model.marker_count(); j += 5) {
    const MarkerPcaModel& m = model.pca[j];
    const std::vector<Vec3> ring = moved_ring(model, j);
    for (int s = 0; s < model.ring_size(j); ++s) {
      std::vector<Vec3> local;
      std::vector<int> slots;
      for (int k = 0; k < model.ring_size(j); ++k)
        if (k != s) {
          local.push_back(ring[k]);
          slots.push_back(k);
        }
      PcaFit fit;
      ASSERT_TRUE(fit.fit(m, slots, local));
      Vec3 reconstructed;
      const double miss = single_gaps.reconstruct(j, s, local, slots, reconstructed);
      EXPECT_LT((reconstructed - fit.reconstruct(m, s)).norm(), 1e-9) << j << " " << s;
      EXPECT_NEAR(miss, fit.squared_miss(m, slots, local), 1e-9 * (1.0 + miss));
      const double variance = fit.predictive_variance(m, s) * m.slot_calibration(s);
      EXPECT_NEAR(single_gaps.variance(model.ring_offsets[j] + s), variance, 1e-9 * variance);
      ++tried;
    }
  }
  EXPECT_GT(tried, 20);
}

// Moving the members moves the reconstruction: the map reads what it is given.
TEST(SingleGapReconstruction, FollowsTheMembers) {
  const SubjectModel model = build_subject(test::make_limb_capture(), {});
  SingleGapReconstruction single_gaps(model);
  const int j = 3 * 8 + 2, s = 0;
  std::vector<Vec3> local;
  std::vector<int> slots;
  for (int k = 1; k < model.ring_size(j); ++k) {
    local.push_back(model.ring_local_reference[model.ring_offsets[j] + k]);
    slots.push_back(k);
  }
  Vec3 at_reference, moved;
  single_gaps.reconstruct(j, s, local, slots, at_reference);
  for (Vec3& p : local) p *= 1.1;  // the ring grown by a tenth
  single_gaps.reconstruct(j, s, local, slots, moved);
  EXPECT_GT((moved - at_reference).norm(), 1.0);
}

TEST(SingleGapReconstruction, AllocatesNothing) {
  const SubjectModel model = build_subject(test::make_limb_capture(), {});
  SingleGapReconstruction single_gaps(model);
  const int j = 3 * 8 + 2;
  const std::vector<Vec3> ring = moved_ring(model, j);
  const std::vector<Vec3> local(ring.begin() + 1, ring.end());
  std::vector<int> slots;
  for (int k = 1; k < model.ring_size(j); ++k) slots.push_back(k);
  Vec3 out;
  test::CountAllocations counter;
  for (int repeat = 0; repeat < 10; ++repeat) single_gaps.reconstruct(j, 0, local, slots, out);
  EXPECT_EQ(counter.count(), 0u);
}

}  // namespace
}  // namespace skinstream
