#include "clients/skinstream/cmd_eval_actor.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <random>
#include <stdexcept>

#include "clients/skinstream/actor_body.h"
#include "clients/skinstream/actor_render.h"
#include "clients/skinstream/default_paths.h"
#include "clients/skinstream/json_output.h"
#include "core/absolute_orientation.h"
#include "core/capture_filler.h"
#include "core/deform/mesh_deformer.h"
#include "core/deform/mesh_edges.h"
#include "core/fitting/marker_priors.h"
#include "core/geometry/triangle_bvh.h"
#include "protocol/files/capture_file.h"
#include "protocol/offline/makehuman.h"
#include "protocol/offline/marker_set_file.h"
#include "protocol/research/png_file.h"

namespace skinstream::cli {

namespace {

// A withheld marker carried by the surface: a point of a triangle and the marker's offset from
// it in the triangle's own frame (first edge, normal x edge, normal).
struct SurfaceAnchor {
  int triangle = -1;
  Vec3 barycentric = Vec3::Zero();
  Vec3 offset = Vec3::Zero();
  double distance_mm = 0.0;  // of the marker from the surface at the reference frame
};

Eigen::Matrix3d triangle_frame(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 e1 = (b - a).normalized();
  const Vec3 n = triangle_normal(a, b, c);
  Eigen::Matrix3d frame;
  frame.col(0) = e1;
  frame.col(1) = n.cross(e1);
  frame.col(2) = n;
  return frame;
}

template <typename Position>
Vec3 anchored_position(const SurfaceAnchor& anchor, const std::vector<Triangle>& triangles, Position&& at) {
  const Triangle& t = triangles[static_cast<size_t>(anchor.triangle)];
  const Vec3 a = at(t[0]), b = at(t[1]), c = at(t[2]);
  const Vec3 point = anchor.barycentric[0] * a + anchor.barycentric[1] * b + anchor.barycentric[2] * c;
  return point + triangle_frame(a, b, c) * anchor.offset;
}

SurfaceAnchor anchor_marker(const Vec3& marker, const std::vector<Vec3>& vertices, const std::vector<Triangle>& triangles,
                            const TriangleBvh& bvh) {
  SurfaceAnchor anchor;
  Vec3 point;
  anchor.distance_mm = bvh.closest(marker, &anchor.triangle, &point);
  const Triangle& t = triangles[static_cast<size_t>(anchor.triangle)];
  closest_point_on_triangle(marker, vertices[t[0]], vertices[t[1]], vertices[t[2]], &anchor.barycentric);
  anchor.offset = triangle_frame(vertices[t[0]], vertices[t[1]], vertices[t[2]]).transpose() * (marker - point);
  return anchor;
}

struct Errors {
  std::vector<double> all;
  std::map<std::string, std::vector<double>> per_marker;
};

nlohmann::ordered_json stats_json(std::vector<double> values) {
  if (values.empty()) return {{"samples", 0}};
  std::sort(values.begin(), values.end());
  const double mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
  const double p95 = values[std::min(values.size() - 1, static_cast<size_t>(0.95 * static_cast<double>(values.size())))];
  return {{"mean_mm", mean}, {"p95_mm", p95}, {"max_mm", values.back()}, {"samples", values.size()}};
}

// Each segment's motion from the reference by Horn's fit of its own markers, or its parent's
// when it has fewer than three: conventional rigid-segment skinning, the vertices blended by
// the same weights as the full method.
class RigidParts {
 public:
  RigidParts(const DeformationModel& model, const SubjectModel& subject) : model_(model), subject_(subject) {}
  void pose(std::span<const Vec3> markers, std::vector<Vec3>& out) {
    const int parts = model_.part_count();
    motion_.assign(static_cast<size_t>(parts), RigidTransform{});
    for (int p = 0; p < parts; ++p) {
      std::vector<Vec3> from, to;
      for (int k = model_.part_member_offsets[p]; k < model_.part_member_offsets[p + 1]; ++k) {
        from.push_back(subject_.reference_positions[model_.part_members[k].marker]);
        to.push_back(markers[model_.part_members[k].marker]);
      }
      const int parent = model_.skeleton.segments[model_.skeleton.part_segment[p]].parent;
      if (from.size() >= 3 || parent < 0) {
        if (from.size() < 3) {  // a root without three markers: all markers
          from = subject_.reference_positions;
          to.assign(markers.begin(), markers.end());
        }
        fit_rigid(from, to, motion_[p]);
      } else {
        motion_[p] = motion_[parent];  // parents come first
      }
    }
    out.resize(model_.reference_vertices.size());
    for (size_t v = 0; v < out.size(); ++v) {
      Vec3 sum = Vec3::Zero();
      for (int k = model_.vertex_influence_offsets[v]; k < model_.vertex_influence_offsets[v + 1]; ++k)
        sum += model_.vertex_influences[k].weight * motion_[model_.vertex_influences[k].part].apply(model_.reference_vertices[v]);
      out[v] = sum;
    }
  }

 private:
  const DeformationModel& model_;
  const SubjectModel& subject_;
  std::vector<RigidTransform> motion_;
};

// Edges stretched or shrunk by more than 1.5 times against the fitted template at rest, the
// body's overall scale (the median edge ratio) removed.
template <typename Position>
double strained_fraction(const std::vector<std::pair<int, int>>& edges, const std::vector<Vec3>& rest, Position&& at) {
  std::vector<double> ratio;
  ratio.reserve(edges.size());
  for (const auto& [i, j] : edges) {
    const double r0 = (rest[i] - rest[j]).norm();
    ratio.push_back(r0 > 0.0 ? (at(i) - at(j)).norm() / r0 : 1.0);
  }
  std::vector<double> sorted = ratio;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
  const double scale = sorted[sorted.size() / 2];
  int strained = 0;
  for (double r : ratio) {
    const double s = r / scale;
    if (s > 1.5 || s < 1.0 / 1.5) ++strained;
  }
  return static_cast<double>(strained) / static_cast<double>(ratio.size());
}

// The folds' markers, fold after fold, each fold spread over the body: markers in a seeded
// random order, each put in the fold (with room left) whose nearest member is farthest from it,
// at the frame where most markers are seen. Random folds of 5 of 41 sometimes take four markers
// of one arm, which leaves that arm's pose to nothing and measures that rather than the surface.
std::vector<int> spread_folds(const Capture& capture, const std::vector<int>& channels, int folds, int per_fold,
                              uint64_t seed) {
  const int markers = static_cast<int>(channels.size());
  int best_frame = 0, best_seen = -1;
  for (int f = 0; f < capture.frame_count; f += std::max(1, capture.frame_count / 200)) {
    int seen = 0;
    for (int c : channels) seen += capture.present(f, c) ? 1 : 0;
    if (seen > best_seen) best_seen = seen, best_frame = f;
  }
  std::vector<int> order(static_cast<size_t>(markers));
  std::iota(order.begin(), order.end(), 0);
  std::mt19937_64 random(seed);
  std::shuffle(order.begin(), order.end(), random);
  std::vector<std::vector<int>> fold(static_cast<size_t>(folds));
  for (int m : order) {
    const Vec3 p = capture.at(best_frame, channels[m]);
    int chosen = -1;
    double farthest = -1.0;
    for (int k = 0; k < folds; ++k) {
      if (static_cast<int>(fold[k].size()) >= per_fold) continue;
      double nearest = 1e12;
      for (int other : fold[k]) {
        const Vec3 q = capture.at(best_frame, channels[other]);
        if (is_present(p) && is_present(q)) nearest = std::min(nearest, (p - q).norm());
      }
      if (nearest > farthest) farthest = nearest, chosen = k;
    }
    fold[static_cast<size_t>(chosen)].push_back(m);
  }
  std::vector<int> out;
  for (const std::vector<int>& f : fold) {
    out.insert(out.end(), f.begin(), f.end());
    for (size_t k = f.size(); k < static_cast<size_t>(per_fold); ++k) out.push_back(-1);  // a short last fold
  }
  return out;
}

}  // namespace

int run_eval_actor(const EvalActorOptions& o, std::FILE* out) {
  const Capture capture = read_capture(o.capture_path);
  const std::vector<int> channels = capture.labelled_points();
  const int markers = static_cast<int>(channels.size());
  if (o.withhold < 1 || o.withhold >= markers - 3)
    throw std::invalid_argument("--withhold " + std::to_string(o.withhold) + " leaves too few of the " + std::to_string(markers) + " markers");
  const int train_frames = static_cast<int>(o.split * capture.frame_count);
  if (train_frames < 2 || train_frames >= capture.frame_count - 1) throw std::invalid_argument("--split leaves no frames to train or test on");
  const std::string mesh = o.mesh_path.empty() ? default_body_dir() + "/makehuman_hm08_body_only.obj" : o.mesh_path;
  const ActorBody body(mesh, o.mesh_frame, default_body_dir());
  const std::vector<MarkerSet> sets = read_marker_sets(o.marker_sets_dir.empty() ? default_marker_sets_dir() : o.marker_sets_dir);

  int folds = (markers + o.withhold - 1) / o.withhold;
  const std::vector<int> order = spread_folds(capture, channels, folds, o.withhold, o.seed);
  if (o.max_folds > 0) folds = std::min(folds, o.max_folds);

  Errors full, lbs, rigid;
  std::vector<double> off_surface, fold_seconds;
  double rest_strain = 0.0, worst_frame_strain = 0.0, worst_frame_strain_lbs = 0.0;
  std::vector<std::string> all_labels;
  for (int c : channels) all_labels.push_back(capture.labels[c]);
  const MarkerPriors all_priors = body.priors(all_labels, sets);
  const int named = all_priors.named;
  const std::string set_name = all_priors.set_name;
  nlohmann::ordered_json fold_reports = nlohmann::ordered_json::array();
  for (int fold = 0; fold < folds; ++fold) {
    std::vector<int> withheld, kept;
    for (int k = 0; k < static_cast<int>(order.size()); ++k) {
      if (order[k] < 0) continue;
      const bool out_now = k >= fold * o.withhold && k < (fold + 1) * o.withhold;
      (out_now ? withheld : kept).push_back(order[k]);
    }
    std::sort(kept.begin(), kept.end());
    std::vector<int> kept_channels;
    for (int k : kept) kept_channels.push_back(channels[k]);
    const Capture train = capture.select(kept_channels, 0, train_frames);
    const Capture test = capture.select(kept_channels, train_frames, capture.frame_count - train_frames);
    const MarkerPriors priors = body.priors(train.labels, sets);
    std::fprintf(stderr, "eval-actor: fold %d of %d: building without %zu markers\n", fold + 1, folds, withheld.size());
    const ActorSubject subject = build_actor_subject(train, body.fit_body(), priors.priors, o.build);
    fold_seconds.push_back(subject.fit_seconds + subject.build_seconds + subject.check_seconds);
    const DeformationModel& model = subject.deformation;
    const std::vector<Triangle>& triangles = model.faces;
    const TriangleBvh bvh(model.reference_vertices, triangles);
    const int reference = subject.fit.frames.front();
    std::vector<SurfaceAnchor> anchors;
    for (int w : withheld) {
      anchors.push_back(anchor_marker(capture.at(reference, channels[w]), model.reference_vertices, triangles, bvh));
      off_surface.push_back(anchors.back().distance_mm);
    }
    const std::vector<std::pair<int, int>> edges = unique_edges(triangles);
    rest_strain = std::max(rest_strain, strained_fraction(edges, model.rest_vertices, [&](int v) { return model.reference_vertices[v]; }));

    if (fold == 0 && !o.render_dir.empty()) {
      std::filesystem::create_directories(o.render_dir);
      MarkerDots dots;
      for (int k : kept) dots.measured.push_back(capture.at(reference, channels[k]));
      for (int w : withheld) dots.withheld.push_back(capture.at(reference, channels[w]));
      write_png(o.render_dir + "/reference.png",
                render_actor(model.reference_vertices, triangles, dots, "reference frame " + std::to_string(reference)));
      write_png(o.render_dir + "/reference_strain.png",
                render_actor(model.reference_vertices, triangles, dots, "edge strain, blue 1 red 1.5", 480,
                             strain_colours(model.reference_vertices, model.rest_vertices, triangles)));
      write_png(o.render_dir + "/fitted_template.png",
                render_actor(subject.fit.reference_vertices, triangles, dots, "fitted template"));
    }
    const Capture filled = fill_capture(subject.model, test, CaptureFillOptions{});
    MeshDeformer full_deformer(model, subject.model, DeformationMode::QuadraticRbf);
    MeshDeformer lbs_deformer(model, subject.model, DeformationMode::Rigid);
    RigidParts rigid_parts(model, subject.model);
    std::vector<float> positions(3 * model.reference_vertices.size()), lbs_positions(positions.size());
    std::vector<Vec3> rigid_positions;
    std::vector<Vec3> now(kept.size());
    for (int f = 0; f < filled.frame_count; f += std::max(1, o.stride)) {
      for (size_t i = 0; i < kept.size(); ++i) now[i] = filled.at(f, static_cast<int>(i));
      if (!full_deformer.deform(now, positions, {}) || !lbs_deformer.deform(now, lbs_positions, {})) continue;
      rigid_parts.pose(now, rigid_positions);
      auto float_at = [](const std::vector<float>& p) {
        return [&p](int v) { return Vec3(p[3 * v], p[3 * v + 1], p[3 * v + 2]); };
      };
      worst_frame_strain = std::max(worst_frame_strain, strained_fraction(edges, model.rest_vertices, float_at(positions)));
      worst_frame_strain_lbs = std::max(worst_frame_strain_lbs, strained_fraction(edges, model.rest_vertices, float_at(lbs_positions)));
      const bool render_now = fold == 0 && !o.render_dir.empty() && (f == 0 || f == filled.frame_count / 2 ||
                                                                       f + o.stride >= filled.frame_count);
      if (render_now) {
        MarkerDots dots;
        for (const Vec3& m : now) dots.measured.push_back(m);
        for (size_t k = 0; k < withheld.size(); ++k) {
          dots.withheld.push_back(capture.at(train_frames + f, channels[withheld[k]]));
          dots.predicted.push_back(anchored_position(anchors[k], triangles, float_at(positions)));
        }
        std::vector<Vec3> deformed(model.reference_vertices.size());
        for (size_t v = 0; v < deformed.size(); ++v) deformed[v] = float_at(positions)(static_cast<int>(v));
        write_png(o.render_dir + "/frame_" + std::to_string(train_frames + f) + ".png",
                  render_actor(deformed, triangles, dots, "frame " + std::to_string(train_frames + f)));
      }
      for (size_t k = 0; k < withheld.size(); ++k) {
        const Vec3 measured = capture.at(train_frames + f, channels[withheld[k]]);
        if (!is_present(measured)) continue;
        const std::string& name = capture.labels[channels[withheld[k]]];
        auto record = [&](Errors& e, const Vec3& predicted) {
          const double d = (predicted - measured).norm();
          e.all.push_back(d);
          e.per_marker[name].push_back(d);
        };
        record(full, anchored_position(anchors[k], triangles, float_at(positions)));
        record(lbs, anchored_position(anchors[k], triangles, float_at(lbs_positions)));
        record(rigid, anchored_position(anchors[k], triangles, [&](int v) { return rigid_positions[v]; }));
      }
    }
    nlohmann::ordered_json withheld_names = nlohmann::ordered_json::array();
    for (int w : withheld) withheld_names.push_back(capture.labels[channels[w]]);
    fold_reports.push_back({{"withheld", withheld_names},
                            {"check", subject.check.ok() ? std::string("plausible") : subject.check.problem},
                            {"fit_rms_mm", subject.fit.rms_mm},
                            {"registration_rms_mm", subject.skeletal_report.registration.after.rms},
                            {"registration_skipped", subject.registration_skipped},
                            {"skeleton_rms_mm", subject.skeletal_report.skeleton_rms_mm},
                            {"fit_seconds", subject.fit_seconds},
                            {"build_seconds", subject.build_seconds}});
  }

  auto row = [&](const char* name, const Errors& e) {
    nlohmann::ordered_json per_marker;
    for (const auto& [marker, values] : e.per_marker) per_marker[marker] = stats_json(values);
    nlohmann::ordered_json r = {{"method", name}};
    r.update(stats_json(e.all));
    r["per_marker"] = per_marker;
    return r;
  };
  nlohmann::ordered_json report = {
      {"capture", o.capture_path},
      {"markers", markers},
      {"marker_set", set_name},
      {"named_markers", named},
      {"train_frames", train_frames},
      {"test_frames", capture.frame_count - train_frames},
      {"stride", o.stride},
      {"withhold", o.withhold},
      {"folds", folds},
      {"rows", {row("full method", full), row("template LBS", lbs), row("rigid parts", rigid)}},
      {"withheld_off_surface_at_reference", stats_json(off_surface)},
      {"edges_strained_over_1.5", {{"at_rest", rest_strain}, {"worst_frame_full", worst_frame_strain}, {"worst_frame_lbs", worst_frame_strain_lbs}}},
      {"build_seconds",  // a fold's subject: fit, build and checks
       {{"mean", std::accumulate(fold_seconds.begin(), fold_seconds.end(), 0.0) / static_cast<double>(fold_seconds.size())},
        {"max", *std::max_element(fold_seconds.begin(), fold_seconds.end())}}},
      {"fold_reports", fold_reports}};
  std::fprintf(out, "%s\n", report.dump(2).c_str());
  if (!o.json) {
    std::fprintf(out, "\n| method | mean mm | p95 mm | max mm |\n|---|---|---|---|\n");
    for (const auto& r : report["rows"])
      std::fprintf(out, "| %s | %.1f | %.1f | %.1f |\n", r["method"].get<std::string>().c_str(), r.value("mean_mm", 0.0),
                   r.value("p95_mm", 0.0), r.value("max_mm", 0.0));
  }
  return 0;
}

}  // namespace skinstream::cli
