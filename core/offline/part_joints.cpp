#include "core/offline/part_joints.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Dense>

#include "core/offline/part_motions.h"
#include "core/precondition.h"

namespace skinstream {
namespace {

constexpr Precondition require_joints{"part joints"};

// A weight this close to 1 means the part owns the marker outright.
constexpr double kOwned = 1.0 - 1e-9;

// The centre of a hinge is pinned down only weakly along its axis; a small pull (relative to the
// turns' own stiffness) towards the parts' closest markers keeps it between them. (Taking the
// centre along the axis from those markers alone, ignoring the turns there, was measured too:
// over 25 synthetic takes the mean vertex error moved by -0.003 to +0.027 mm, 20 of them up.)
constexpr double kCentrePrior = 1e-3;

}  // namespace

std::vector<PartJoint> fit_part_joints(std::span<const Vec3> reference, std::span<const int> part_member_offsets,
                                       std::span<const PartMember> part_members, std::span<const Vec3> training,
                                       int frame_count, const PartJointOptions& options) {
  const int m = static_cast<int>(reference.size());
  require_joints(m > 0, "no markers");
  require_joints(frame_count > 0 && training.size() == static_cast<size_t>(frame_count) * m,
          "training is not frame_count x marker_count");
  require_joints(options.max_residual_ratio > 0.0 && std::isfinite(options.max_residual_ratio),
          "max_residual_ratio must be > 0");
  require_joints(options.max_axis_spread > 0.0 && std::isfinite(options.max_axis_spread), "max_axis_spread must be > 0");
  require_joints(!part_member_offsets.empty() && part_member_offsets.front() == 0 &&
              part_member_offsets.back() == static_cast<int>(part_members.size()),
          "part member offsets do not span the members");
  for (int i = 0; i < m; ++i) require_joints(reference[i].allFinite(), "reference marker " + std::to_string(i) + " is not finite");
  for (size_t k = 0; k < training.size(); ++k)
    require_joints(training[k].allFinite(), "marker " + std::to_string(k % m) + " is not finite at frame " + std::to_string(k / m));

  const int part_count = static_cast<int>(part_member_offsets.size()) - 1;
  std::vector<std::vector<int>> members(part_count), fitted(part_count);
  for (int p = 0; p < part_count; ++p) {
    require_joints(part_member_offsets[p] <= part_member_offsets[p + 1], "part member offsets decrease at part " + std::to_string(p));
    for (int k = part_member_offsets[p]; k < part_member_offsets[p + 1]; ++k) {
      const int i = part_members[k].marker;
      require_joints(i >= 0 && i < m, "part " + std::to_string(p) + " names marker " + std::to_string(i) + " of " + std::to_string(m));
      members[p].push_back(i);
      if (part_members[k].weight >= kOwned) fitted[p].push_back(i);
    }
    if (fitted[p].size() < 3) fitted[p] = members[p];
  }

  // Each part's rigid motion per frame, and the centroid of the markers it is fitted to.
  const std::vector<RigidTransform> motion = fit_part_motions(reference, fitted, training, frame_count);
  std::vector<Vec3> centroid(part_count, Vec3::Zero());
  for (int p = 0; p < part_count; ++p)
    for (int i : fitted[p]) centroid[p] += reference[i] / static_cast<double>(fitted[p].size());

  std::vector<PartJoint> joints;
  for (int a = 0; a < part_count; ++a) {
    for (int b = a + 1; b < part_count; ++b) {
      if (members[a].empty() || members[b].empty()) continue;
      const RigidTransform* ma = &motion[static_cast<size_t>(a) * frame_count];
      const RigidTransform* mb = &motion[static_cast<size_t>(b) * frame_count];
      // Least squares over frames: (R_a - R_b) c = t_b - t_a.
      Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
      Vec3 rhs = Vec3::Zero();
      for (int f = 0; f < frame_count; ++f) {
        const Eigen::Matrix3d d = ma[f].rotation - mb[f].rotation;
        normal += d.transpose() * d;
        rhs += d.transpose() * (mb[f].translation - ma[f].translation);
      }
      double closest = std::numeric_limits<double>::infinity();
      Vec3 prior = Vec3::Zero();
      for (int i : members[a])
        for (int j : members[b])
          if (const double d = (reference[i] - reference[j]).squaredNorm(); d < closest)
            closest = d, prior = 0.5 * (reference[i] + reference[j]);
      const Vec3 lambda =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(normal, Eigen::EigenvaluesOnly).eigenvalues();  // ascending
      if (!(lambda[2] > 0.0)) continue;  // the two parts never turn against each other
      const double spread = std::max(lambda[0], 0.0) / lambda[2];
      if (!(spread <= options.max_axis_spread)) continue;
      const double pull = kCentrePrior * normal.trace() / 3.0;
      const Vec3 centre = (normal + pull * Eigen::Matrix3d::Identity()).ldlt().solve(rhs + pull * prior);

      double residual = 0.0, relative = 0.0;
      const size_t member_count = members[a].size() + members[b].size();
      for (int f = 0; f < frame_count; ++f) {
        residual += (ma[f].apply(centre) - mb[f].apply(centre)).squaredNorm();
        for (const auto* list : {&members[a], &members[b]})
          for (int i : *list) relative += (ma[f].apply(reference[i]) - mb[f].apply(reference[i])).squaredNorm();
      }
      residual = std::sqrt(residual / frame_count);
      relative = std::sqrt(relative / (static_cast<double>(frame_count) * member_count));
      if (!(residual <= options.max_residual_ratio * relative)) continue;
      const Vec3 between = centroid[b] - centroid[a];
      if (!(between.norm() > 0.0)) continue;
      joints.push_back({a, b, centre, between.normalized(), residual, relative, spread});
    }
  }
  return joints;
}

}  // namespace skinstream
