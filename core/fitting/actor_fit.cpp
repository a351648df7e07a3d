#include "core/fitting/actor_fit.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/deform/skeleton_solver.h"
#include "core/fitting/initial_alignment.h"
#include "core/geometry/triangle_bvh.h"

namespace skinstream {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Everything the fit changes, and what follows from it.
class Fit {
 public:
  Fit(const FitBody& body, std::span<const Vec3> frames, int frame_count, int marker_count,
      std::span<const MarkerPrior> priors, const ActorFitOptions& options)
      : body_(body),
        triangles_(body.triangles),
        frames_(frames),
        frame_count_(frame_count),
        marker_count_(marker_count),
        priors_(priors),
        options_(options),
        vertex_weights_(body.weights),
        attachments_(static_cast<size_t>(marker_count), MarkerAttachment{-1}) {
    solver_options_.robust_mm = options.robust_mm;
    solver_options_.prior = options.pose_prior;
    solver_options_.twist_prior = options.twist_prior;
    solver_options_.twist_axes = body.twist_axes;
    if (proportionable()) proportions_ = BodyProportions::neutral(*body.segments);
    set_proportions(proportions_);
  }

  bool proportionable() const { return body_.bones != nullptr && body_.segments != nullptr; }
  int segment_count() const { return body_.segment_count(); }
  const Vec3* frame(int f) const { return frames_.data() + static_cast<size_t>(f) * marker_count_; }

  void set_proportions(const BodyProportions& p) {
    proportions_ = p;
    if (proportionable()) {
      maps_ = proportion_bones(body_.bones->skeleton, *body_.segments, p);
      rest_ = proportioned_vertices(body_.bones->rest, body_.bones->weights, maps_);
      pivots_ = proportioned_pivots(body_.bones->skeleton, *body_.segments, maps_);
    } else {
      rest_ = body_.rest;
      pivots_ = body_.rest_pivots;
    }
    rest_bvh_valid_ = false;
  }

  // The markers' rest positions and the runtime skeleton for the current proportions and places.
  // Markers not yet placed ride with the pelvis at its pivot (their measurements are left out).
  SegmentSkeleton skeleton(std::vector<Vec3>& rest_markers, const std::vector<Vec3>* rest = nullptr,
                           const std::vector<Vec3>* pivots = nullptr) const {
    const std::vector<Vec3>& vertices = rest ? *rest : rest_;
    const std::vector<Vec3>& joints = pivots ? *pivots : pivots_;
    SegmentSkeleton s;
    for (int k = 0; k < segment_count(); ++k) s.segments.push_back({body_.segment_names[k], body_.segment_parents[k], joints[k]});
    rest_markers.resize(static_cast<size_t>(marker_count_));
    for (int i = 0; i < marker_count_; ++i) {
      const MarkerAttachment& a = attachments_[i];
      if (a.triangle < 0) {
        rest_markers[i] = joints[0];
        s.marker_weights.push_back({0, 1.0});
      } else {
        rest_markers[i] = attached_position(a, vertices, triangles_);
        attachment_segment_weights(a, triangles_, vertex_weights_, s.marker_weights);
      }
      s.marker_weight_offsets.push_back(static_cast<int>(s.marker_weights.size()));
    }
    return s;
  }

  // A frame's measurements with the unplaced markers left out.
  void measured(int f, std::vector<Vec3>& out) const {
    out.assign(frame(f), frame(f) + marker_count_);
    for (int i = 0; i < marker_count_; ++i)
      if (attachments_[i].triangle < 0) out[i] = missing_point();
  }

  // The pose prior's pull: strong while the body is first put in place (far from the actor's
  // pose, where an unseen twist can wind up), light once the pose is near.
  void set_pose_prior(double prior) {
    solver_options_.prior = prior;
    solver_options_.twist_prior = std::max(prior, options_.twist_prior);
  }

  SegmentPose solve_pose(const SegmentPose& start, int f, int iterations) {
    std::vector<Vec3> rest_markers, now;
    const SegmentSkeleton s = skeleton(rest_markers);
    SkeletonSolverOptions o = solver_options_;
    o.max_iterations = iterations;
    SkeletonSolver solver(s, rest_markers, o);
    solver.set_pose(start.local, start.translation);
    measured(f, now);
    solver.solve(now);
    return {solver.local_rotations(), solver.root_translation()};
  }

  std::vector<RigidTransform> motions(const SegmentPose& pose) const {
    std::vector<Vec3> rest_markers;
    const SegmentSkeleton s = skeleton(rest_markers);
    SkeletonSolver solver(s, rest_markers);
    solver.set_pose(pose.local, pose.translation);
    std::vector<RigidTransform> out;
    for (int s = 0; s < segment_count(); ++s) out.push_back(solver.segment_motion(s));
    return out;
  }

  // First guesses: the named markers' defined places onto the reference frame (trunk and head
  // when four or more of them are there), scale then rotation; or the blind search's best few.
  std::vector<Similarity> initial_guesses(int reference, std::span<const Vec3> ups, bool* blind) const {
    const Vec3* measured = frame(reference);
    std::vector<Vec3> points(static_cast<size_t>(marker_count_), missing_point());
    std::vector<Vec3> trunk(points);
    int named = 0, trunk_named = 0;
    for (int i = 0; i < marker_count_; ++i) {
      const MarkerAttachment& place = priors_[i].place;
      if (place.triangle < 0 || !is_present(measured[i])) continue;
      points[i] = attached_position(place, body_.rest, triangles_);
      ++named;
      std::vector<SegmentWeight> w;
      attachment_segment_weights(place, triangles_, vertex_weights_, w);
      const auto dominant = std::max_element(w.begin(), w.end(), [](auto& a, auto& b) { return a.weight < b.weight; });
      const std::string& name = body_.segment_names[dominant->segment];
      if (name == "pelvis" || name == "abdomen" || name == "chest" || name == "head") {
        trunk[i] = points[i];
        ++trunk_named;
      }
    }
    *blind = named < 3;
    if (options_.start) return {*options_.start};
    const std::vector<Vec3> seen(measured, measured + marker_count_);
    if (!*blind) return {align_named(trunk_named >= 4 ? trunk : points, seen)};
    std::vector<Similarity> out;
    for (const BlindAlignment& b : align_blind(body_.rest, triangles_, seen, ups)) {
      out.push_back(b.similarity);
      if (out.size() == 4) break;
    }
    return out;
  }

  // The pose with each upper arm turned from its rest direction to the given one (left, right;
  // rest-pose axes; not finite leaves it at rest). Its parents are at rest in `pose`, so the
  // turn is its local rotation.
  SegmentPose with_arms_turned(SegmentPose pose, const std::array<Vec3, 2>& direction) const {
    for (const char* name : {"upperarm.L", "upperarm.R"}) {
      const int arm = body_.find(name);
      if (arm < 0) continue;
      int child = -1;
      for (int s = 0; s < segment_count(); ++s)
        if (body_.segment_parents[s] == arm) child = s;
      if (child < 0) continue;
      const Vec3 bone = pivots_[child] - pivots_[arm];
      const Vec3& to = direction[pivots_[arm].x() < 0.0 ? 0 : 1];  // left is -X
      if (!to.allFinite() || to.norm() <= 0.0 || bone.norm() <= 0.0) continue;
      pose.local[static_cast<size_t>(arm)] = Eigen::Quaterniond::FromTwoVectors(bone, to).toRotationMatrix();
    }
    return pose;
  }

  // Sets the overall scale from a guess and returns the pelvis pose that places the template.
  SegmentPose pose_from(const Similarity& similarity) {
    BodyProportions p = proportionable() ? BodyProportions::neutral(*body_.segments) : BodyProportions{};
    p.overall = proportionable() ? std::clamp(similarity.scale, 0.5, 2.0) : 1.0;  // a scan keeps its size
    first_overall_ = p.overall;
    set_proportions(p);
    SegmentPose pose{std::vector<Eigen::Matrix3d>(static_cast<size_t>(segment_count()), Eigen::Matrix3d::Identity()), Vec3::Zero()};
    const Eigen::Matrix3d rotation = similarity.rigid.rotation;
    // similarity(x) = R (s x) + T and the proportioned template is h + s (x - h) about the
    // pelvis pivot h, so the pelvis motion is x -> R x + T + (s - 1) R h.
    const Vec3 h = pivots_[0];
    const Vec3 translation = similarity.rigid.translation + (p.overall - 1.0) * (rotation * h);
    pose.local[0] = rotation;
    pose.translation = translation + rotation * h - h;  // P_0 - R pivot_0 = translation, P_0 = pivot_0 + t
    return pose;
  }

  // How far the placed markers of frame f are from where the pose puts them (RMS, mm).
  double miss(const SegmentPose& pose, int f) const {
    std::vector<Vec3> rest_markers, now;
    const SegmentSkeleton s = skeleton(rest_markers);
    SkeletonSolver solver(s, rest_markers);
    solver.set_pose(pose.local, pose.translation);
    measured(f, now);
    double sum = 0.0;
    int count = 0;
    for (int i = 0; i < marker_count_; ++i)
      if (is_present(now[i])) {
        sum += (solver.predicted_marker(i) - now[i]).squaredNorm();
        ++count;
      }
    return count > 0 ? std::sqrt(sum / count) : std::numeric_limits<double>::infinity();
  }

  // Unplaced markers (no defined place, or all of them in a blind fit) go where the posed
  // surface is nearest to their measurement in frame f.
  void attach_nearest(const SegmentPose& pose, int f, bool only_unknown) {
    const std::vector<Vec3> posed = pose_vertices(rest_, vertex_weights_, motions(pose));
    const TriangleBvh bvh(posed, std::vector<Triangle>(triangles_.begin(), triangles_.end()));
    for (int i = 0; i < marker_count_; ++i) {
      if (only_unknown && priors_[i].place.triangle >= 0) continue;
      const Vec3 m = frame(f)[i];
      if (!is_present(m)) continue;
      int triangle = -1;
      bvh.closest(m, &triangle);
      const Triangle& t = triangles_[static_cast<size_t>(triangle)];
      MarkerAttachment a;
      a.triangle = triangle;
      closest_point_on_triangle(m, posed[t[0]], posed[t[1]], posed[t[2]], &a.barycentric);
      a.offset_mm = options_.marker_offset_mm;
      attachments_[i] = a;
    }
  }

  void place_defined() {
    for (int i = 0; i < marker_count_; ++i)
      if (priors_[i].place.triangle >= 0) {
        attachments_[i] = priors_[i].place;
        attachments_[i].offset_mm = options_.marker_offset_mm;
      }
  }

  // Each marker's measurements over the fit frames, carried back to the rest pose through its
  // current segments, their median, and the nearest allowed surface point to it.
  void update_places(const std::vector<int>& fit_frames, const std::vector<SegmentPose>& poses) {
    std::vector<std::vector<RigidTransform>> motion;
    for (const SegmentPose& p : poses) motion.push_back(motions(p));
    if (!rest_bvh_valid_) {
      rest_bvh_ = TriangleBvh(rest_, std::vector<Triangle>(triangles_.begin(), triangles_.end()));
      rest_bvh_valid_ = true;
    }
    std::vector<SegmentWeight> w;
    std::vector<double> xs, ys, zs;
    for (int i = 0; i < marker_count_; ++i) {
      if (attachments_[i].triangle < 0) continue;
      w.clear();
      attachment_segment_weights(attachments_[i], triangles_, vertex_weights_, w);
      xs.clear();
      ys.clear();
      zs.clear();
      for (size_t k = 0; k < fit_frames.size(); ++k) {
        const Vec3 m = frame(fit_frames[k])[i];
        if (!is_present(m)) continue;
        BoneMap blended = BoneMap::Zero();
        for (const SegmentWeight& sw : w) {
          const RigidTransform& r = motion[k][sw.segment];
          blended.leftCols<3>() += sw.weight * r.rotation;
          blended.col(3) += sw.weight * r.translation;
        }
        const Vec3 back = blended.leftCols<3>().inverse() * (m - blended.col(3));
        xs.push_back(back.x());
        ys.push_back(back.y());
        zs.push_back(back.z());
      }
      if (xs.empty()) continue;
      auto median = [](std::vector<double>& v) {
        std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
        return v[v.size() / 2];
      };
      const Vec3 target(median(xs), median(ys), median(zs));
      MarkerAttachment a;
      Vec3 point;
      const std::vector<int>& allowed = priors_[i].allowed_triangles;
      if (allowed.empty()) {
        rest_bvh_.closest(target, &a.triangle, &point);
      } else {
        double best = std::numeric_limits<double>::infinity();
        for (int t : allowed) {
          const Triangle& tri = triangles_[static_cast<size_t>(t)];
          const Vec3 p = closest_point_on_triangle(target, rest_[tri[0]], rest_[tri[1]], rest_[tri[2]]);
          const double d = (p - target).squaredNorm();
          if (d < best) {
            best = d;
            a.triangle = t;
            point = p;
          }
        }
      }
      const Triangle& t = triangles_[static_cast<size_t>(a.triangle)];
      closest_point_on_triangle(target, rest_[t[0]], rest_[t[1]], rest_[t[2]], &a.barycentric);
      a.offset_mm = options_.marker_offset_mm;
      attachments_[i] = a;
    }
  }

  // The proportions: damped Gauss-Newton in log scales over the fit frames, poses held.
  void update_proportions(const std::vector<int>& fit_frames, const std::vector<SegmentPose>& poses) {
    if (!proportionable()) return;
    const int groups = static_cast<int>(body_.segments->shape_groups.size());
    const int unknowns = 1 + 2 * groups;
    auto to_vector = [&](const BodyProportions& p) {
      Eigen::VectorXd x(unknowns);
      x[0] = std::log(p.overall);
      for (int g = 0; g < groups; ++g) {
        x[1 + g] = std::log(p.length[g]);
        x[1 + groups + g] = std::log(p.girth[g]);
      }
      return x;
    };
    auto from_vector = [&](const Eigen::VectorXd& x) {
      BodyProportions p = BodyProportions::neutral(*body_.segments);
      p.overall = std::exp(x[0]);
      for (int g = 0; g < groups; ++g) {
        p.length[g] = std::exp(x[1 + g]);
        p.girth[g] = std::exp(x[1 + groups + g]);
      }
      return p;
    };
    // Robust weights from the current misses, held through the step (reweighted least squares).
    std::vector<double> robust;
    {
      const Eigen::VectorXd r = residuals(to_vector(proportions_), from_vector, fit_frames, poses, nullptr);
      for (int k = 0; k + 2 < r.size() - 2 * groups - 1; k += 3) {
        const double miss = r.segment<3>(k).norm();
        robust.push_back(miss > options_.robust_mm ? std::sqrt(options_.robust_mm / miss) : 1.0);
      }
    }
    Eigen::VectorXd x = to_vector(proportions_);
    Eigen::VectorXd r = residuals(x, from_vector, fit_frames, poses, &robust);
    double cost = r.squaredNorm();
    double damping = 1e-3;
    for (int step = 0; step < 4; ++step) {
      Eigen::MatrixXd jacobian(r.size(), unknowns);
      for (int u = 0; u < unknowns; ++u) {
        Eigen::VectorXd moved = x;
        moved[u] += 1e-4;
        jacobian.col(u) = (residuals(moved, from_vector, fit_frames, poses, &robust) - r) / 1e-4;
      }
      const Eigen::MatrixXd normal = jacobian.transpose() * jacobian;
      const Eigen::VectorXd gradient = jacobian.transpose() * r;
      bool improved = false;
      for (int attempt = 0; attempt < 6 && !improved; ++attempt) {
        Eigen::MatrixXd damped = normal;
        damped.diagonal() += damping * normal.diagonal() + Eigen::VectorXd::Constant(unknowns, 1e-6);
        Eigen::VectorXd delta = damped.ldlt().solve(-gradient);
        const double largest = delta.cwiseAbs().maxCoeff();
        if (largest > 0.2) delta *= 0.2 / largest;  // at most a fifth of a log unit a step
        const Eigen::VectorXd trial = within_human_range(x + delta);
        const Eigen::VectorXd tr = residuals(trial, from_vector, fit_frames, poses, &robust);
        if (tr.squaredNorm() < cost) {
          x = trial;
          r = tr;
          cost = tr.squaredNorm();
          damping = std::max(1e-6, damping / 3.0);
          improved = true;
        } else {
          damping *= 10.0;
        }
      }
      if (!improved) break;
    }
    set_proportions(from_vector(x));
  }

  // Proportions no adult or teenager has are not offered to the data, however a few markers pull:
  // each group's length within 0.75-1.35 of the template's, its girth within 0.8-1.25 of its
  // length (the template is an average adult; the overall scale is free within 0.5-2).
  Eigen::VectorXd within_human_range(Eigen::VectorXd x) const {
    const int groups = static_cast<int>(body_.segments->shape_groups.size());
    x[0] = std::clamp(x[0], std::log(0.5), std::log(2.0));
    for (int g = 0; g < groups; ++g) {
      x[1 + g] = std::clamp(x[1 + g], std::log(0.75), std::log(1.35));
      x[1 + groups + g] = std::clamp(x[1 + groups + g], x[1 + g] + std::log(0.8), x[1 + g] + std::log(1.25));
    }
    return x;
  }

  template <typename FromVector>
  Eigen::VectorXd residuals(const Eigen::VectorXd& x, const FromVector& from_vector, const std::vector<int>& fit_frames,
                            const std::vector<SegmentPose>& poses, const std::vector<double>* robust) const {
    const BodyProportions p = from_vector(x);
    const std::vector<BoneMap> maps = proportion_bones(body_.bones->skeleton, *body_.segments, p);
    const std::vector<Vec3> pivots = proportioned_pivots(body_.bones->skeleton, *body_.segments, maps);
    // Only the vertices under the markers need proportioning.
    std::vector<Vec3> rest = rest_;
    for (const MarkerAttachment& a : attachments_)
      if (a.triangle >= 0)
        for (int v : triangles_[static_cast<size_t>(a.triangle)])
          rest[v] = proportioned_vertex(body_.bones->rest[v], body_.bones->weights, v, maps);
    std::vector<Vec3> rest_markers;
    const SegmentSkeleton s = skeleton(rest_markers, &rest, &pivots);
    SkeletonSolver solver(s, rest_markers);
    std::vector<double> out;
    size_t k = 0;
    for (size_t f = 0; f < fit_frames.size(); ++f) {
      solver.set_pose(poses[f].local, poses[f].translation);
      const Vec3* m = frame(fit_frames[f]);
      for (int i = 0; i < marker_count_; ++i) {
        if (attachments_[i].triangle < 0 || !is_present(m[i])) continue;
        const double w = robust ? (*robust)[k++] : 1.0;
        const Vec3 d = w * (solver.predicted_marker(i) - m[i]);
        out.insert(out.end(), {d.x(), d.y(), d.z()});
      }
    }
    const int groups = static_cast<int>(body_.segments->shape_groups.size());
    // The overall scale is held to its first guess as the lengths are to the template's: without
    // it, the body could shrink all over while the groups the markers see grow back, leaving the
    // groups no marker sees (the arms of a lower-body set) too small.
    out.push_back(std::sqrt(options_.length_prior) * (x[0] - std::log(first_overall_)));
    for (int g = 0; g < groups; ++g) out.push_back(std::sqrt(options_.length_prior) * x[1 + g]);
    for (int g = 0; g < groups; ++g) out.push_back(std::sqrt(options_.girth_prior) * (x[1 + groups + g] - x[1 + g]));
    return Eigen::Map<const Eigen::VectorXd>(out.data(), static_cast<long>(out.size()));
  }

  const FitBody& body_;
  std::span<const Triangle> triangles_;
  std::span<const Vec3> frames_;
  int frame_count_;
  int marker_count_;
  std::span<const MarkerPrior> priors_;
  ActorFitOptions options_;
  SkeletonSolverOptions solver_options_;

 public:
  VertexSegmentWeights vertex_weights_;
  BodyProportions proportions_;
  std::vector<BoneMap> maps_;
  std::vector<Vec3> rest_;
  std::vector<Vec3> pivots_;
  std::vector<MarkerAttachment> attachments_;

 private:
  TriangleBvh rest_bvh_;
  bool rest_bvh_valid_ = false;
  double first_overall_ = 1.0;
};

double pose_distance(const SegmentPose& a, const SegmentPose& b) {
  double sum = 0.0;
  for (size_t s = 0; s < a.local.size(); ++s) {
    const double c = std::clamp(((a.local[s].transpose() * b.local[s]).trace() - 1.0) / 2.0, -1.0, 1.0);
    sum += std::acos(c);
  }
  return sum;
}

}  // namespace

std::vector<Vec3> pose_vertices(const std::vector<Vec3>& rest_vertices, const VertexSegmentWeights& weights,
                                const std::vector<RigidTransform>& segment_motions) {
  std::vector<Vec3> out(rest_vertices.size());
  for (size_t v = 0; v < rest_vertices.size(); ++v) {
    Vec3 p = Vec3::Zero();
    for (int k = weights.offsets[v]; k < weights.offsets[v + 1]; ++k)
      p += weights.weights[static_cast<size_t>(k)].weight *
           segment_motions[static_cast<size_t>(weights.weights[static_cast<size_t>(k)].segment)].apply(rest_vertices[v]);
    out[v] = p;
  }
  return out;
}

int FitBody::find(const std::string& name) const {
  for (int s = 0; s < segment_count(); ++s)
    if (segment_names[s] == name) return s;
  return -1;
}

FitBody fit_body_of(const Body& body, const TemplateSegments& segments) {
  FitBody out;
  out.rest = body.rest;
  out.triangles = triangulate(body.faces);
  out.weights = segment_weights(body.weights, segments);
  for (const TemplateSegment& s : segments.segments) {
    out.segment_names.push_back(s.name);
    out.segment_parents.push_back(s.parent);
    const Bone& bone = body.skeleton.bone(s.first_bone);
    out.rest_pivots.push_back(bone.head);
    // Limbs twist about their bone; the trunk's segments have no twist of their own to hold.
    const bool limb = s.name.find('.') != std::string::npos && s.name.rfind("clavicle", 0) != 0;
    out.twist_axes.push_back(limb && bone.length() > 0.0 ? bone.axis() : Vec3::Zero());
  }
  out.bones = &body;
  out.segments = &segments;
  return out;
}

ActorFit fit_actor(const FitBody& body, std::span<const Vec3> frames, int frame_count, int marker_count,
                   int reference_frame, std::span<const MarkerPrior> priors, const ActorFitOptions& options) {
  if (frame_count <= 0 || marker_count <= 0 || frames.size() != static_cast<size_t>(frame_count) * marker_count)
    throw std::invalid_argument("fit_actor: " + std::to_string(frames.size()) + " positions for " +
                                std::to_string(frame_count) + " frames of " + std::to_string(marker_count) + " markers");
  if (reference_frame < 0 || reference_frame >= frame_count) throw std::invalid_argument("fit_actor: no such reference frame");
  if (static_cast<int>(priors.size()) != marker_count) throw std::invalid_argument("fit_actor: one marker prior per marker is needed");
  if (body.weights.vertex_count() != static_cast<int>(body.rest.size()) || body.segment_count() == 0 ||
      body.rest_pivots.size() != body.segment_names.size() || body.segment_parents.size() != body.segment_names.size() ||
      body.twist_axes.size() != body.segment_names.size())
    throw std::invalid_argument("fit_actor: the body has no skin weights or an inconsistent skeleton");

  Fit fit(body, frames, frame_count, marker_count, priors, options);
  ActorFit out;

  // 1. The reference frame: first guesses, each posed with the markers placed where the posed
  // surface is nearest, iterated (articulated closest points); the one that fits best is kept.
  const std::vector<Similarity> guesses = fit.initial_guesses(reference_frame, capture_up(frames, frame_count, marker_count), &out.blind);
  SegmentPose reference;
  double best = std::numeric_limits<double>::infinity();
  std::vector<MarkerAttachment> best_places;
  BodyProportions best_proportions;
  const size_t starts = guesses.size() * (1 + options.arm_starts.size());
  for (size_t start = 0; start < starts; ++start) {
    const Similarity& guess = guesses[start % guesses.size()];
    SegmentPose pose = fit.pose_from(guess);
    if (start >= guesses.size())
      pose = fit.with_arms_turned(pose, options.arm_starts[start / guesses.size() - 1]);
    fit.attachments_.assign(static_cast<size_t>(marker_count), MarkerAttachment{-1});
    fit.place_defined();
    if (out.blind) fit.attach_nearest(pose, reference_frame, false);
    for (int round = 0; round < 8; ++round) {
      pose = fit.solve_pose(pose, reference_frame, 40);
      fit.attach_nearest(pose, reference_frame, !out.blind);
    }
    pose = fit.solve_pose(pose, reference_frame, 40);
    const double miss = fit.miss(pose, reference_frame);
    if (miss < best) {
      best = miss;
      reference = pose;
      best_places = fit.attachments_;
      best_proportions = fit.proportions_;
    }
  }
  fit.attachments_ = best_places;
  fit.set_proportions(best_proportions);
  fit.set_pose_prior(options.tracking_pose_prior);

  // 2. Track the take from the reference frame both ways, then choose the spread of fit frames.
  std::vector<SegmentPose> tracked(static_cast<size_t>(frame_count));
  std::vector<char> have(static_cast<size_t>(frame_count), 0);
  tracked[reference_frame] = reference;
  have[reference_frame] = 1;
  const int stride = std::max(1, options.track_stride);
  for (int direction : {1, -1}) {
    SegmentPose pose = reference;
    for (int f = reference_frame + direction * stride; f >= 0 && f < frame_count; f += direction * stride) {
      int present = 0;
      for (int i = 0; i < marker_count; ++i) present += is_present(fit.frame(f)[i]) ? 1 : 0;
      if (present < marker_count / 2) continue;  // too little seen to trust the pose
      pose = fit.solve_pose(pose, f, 6);
      tracked[f] = pose;
      have[f] = 1;
      ++out.tracked_frames;
    }
  }
  out.frames = {reference_frame};
  std::vector<double> nearest(static_cast<size_t>(frame_count), std::numeric_limits<double>::infinity());
  for (int k = 1; k < options.fit_frames; ++k) {
    const int last = out.frames.back();
    int best = -1;
    for (int f = 0; f < frame_count; ++f) {
      if (!have[f]) continue;
      nearest[f] = std::min(nearest[f], pose_distance(tracked[f], tracked[last]));
      if (nearest[f] > 1e-3 && (best < 0 || nearest[f] > nearest[best])) best = f;
    }
    if (best < 0) break;
    out.frames.push_back(best);
  }
  for (int f : out.frames) out.poses.push_back(tracked[f]);

  // 3. Rounds of proportions, poses and places over the fit frames.
  for (int round = 0; round < options.rounds; ++round) {
    fit.update_proportions(out.frames, out.poses);
    for (size_t k = 0; k < out.frames.size(); ++k) out.poses[k] = fit.solve_pose(out.poses[k], out.frames[k], 20);
    fit.update_places(out.frames, out.poses);
    for (size_t k = 0; k < out.frames.size(); ++k) out.poses[k] = fit.solve_pose(out.poses[k], out.frames[k], 20);
  }

  // What was fitted, and how well.
  out.proportions = fit.proportions_;
  out.attachments = fit.attachments_;
  out.rest_vertices = fit.rest_;
  out.rest_pivots = fit.pivots_;
  out.vertex_weights = fit.vertex_weights_;
  out.reference_motions = fit.motions(out.poses[0]);
  const std::vector<RigidTransform>& at_reference = out.reference_motions;
  out.reference_vertices = pose_vertices(out.rest_vertices, out.vertex_weights, at_reference);
  std::vector<Vec3> rest_markers;
  out.reference_skeleton = fit.skeleton(rest_markers);
  for (int s = 0; s < body.segment_count(); ++s)
    out.reference_skeleton.segments[s].pivot = at_reference[s].apply(out.rest_pivots[s]);
  std::vector<double> sum(static_cast<size_t>(marker_count), 0.0);
  std::vector<int> count(static_cast<size_t>(marker_count), 0);
  double total = 0.0;
  int samples = 0;
  for (size_t k = 0; k < out.frames.size(); ++k) {
    const SegmentSkeleton rest_skeleton = fit.skeleton(rest_markers);
    SkeletonSolver solver(rest_skeleton, rest_markers);
    solver.set_pose(out.poses[k].local, out.poses[k].translation);
    for (int i = 0; i < marker_count; ++i) {
      const Vec3 m = fit.frame(out.frames[k])[i];
      if (!is_present(m) || out.attachments[i].triangle < 0) continue;
      const double d2 = (solver.predicted_marker(i) - m).squaredNorm();
      sum[i] += d2;
      ++count[i];
      total += d2;
      ++samples;
    }
  }
  for (int i = 0; i < marker_count; ++i) out.marker_rms_mm.push_back(count[i] > 0 ? std::sqrt(sum[i] / count[i]) : kNaN);
  out.rms_mm = samples > 0 ? std::sqrt(total / samples) : kNaN;
  return out;
}

}  // namespace skinstream
