#include "core/synth/synth_capture.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/geometry/triangle_bvh.h"
#include "core/synth/motion.h"
#include "core/synth/random.h"
#include "core/synth/subdivision.h"

namespace skinstream::synth {

struct SynthCapture::Scene {
  DeformedSurface surface;  // the chosen mesh
  std::vector<Face> faces;
  std::vector<Pose> poses;
  std::vector<EffectFrame> effects;
  Skeleton skeleton;
};

int SynthCapture::mesh_vertex_count() const { return scene_ ? scene_->surface.vertex_count() : 0; }

const std::vector<Triangle>& SynthCapture::mesh_triangles() const {
  static const std::vector<Triangle> none;
  return scene_ ? scene_->surface.triangles() : none;
}

const std::vector<Face>& SynthCapture::mesh_faces() const {
  static const std::vector<Face> none;
  return scene_ ? scene_->faces : none;
}

const Pose& SynthCapture::pose(int frame) const {
  if (!scene_ || frame < 0 || frame >= static_cast<int>(scene_->poses.size()))
    throw std::out_of_range("SynthCapture::pose: frame " + std::to_string(frame));
  return scene_->poses[static_cast<size_t>(frame)];
}

std::vector<Vec3> SynthCapture::pose_mesh(int frame, bool skin_only) const {
  const Pose& p = pose(frame);
  std::vector<Vec3> out;
  scene_->surface.pose(pose_bones(scene_->skeleton, p), scene_->effects[static_cast<size_t>(frame)], out,
                       skin_only);
  return out;
}

namespace {

void check_options(const SynthOptions& o) {
  if (!is_motion(o.motion)) throw std::invalid_argument("synth: unknown motion '" + o.motion + "'");
  if (!(o.seconds > 0.0) || !std::isfinite(o.seconds))
    throw std::invalid_argument("synth: seconds must be positive");
  if (!(o.rate_hz > 0.0) || !std::isfinite(o.rate_hz))
    throw std::invalid_argument("synth: rate must be positive");
  if (o.seconds * o.rate_hz > 2.0e6) throw std::invalid_argument("synth: take too long");
  if (o.markers < 1) throw std::invalid_argument("synth: markers must be at least 1");
  if (!(o.marker_offset_mm >= 0.0)) throw std::invalid_argument("synth: marker offset must not be negative");
  if (!(o.breaking.noise_mm >= 0.0)) throw std::invalid_argument("synth: noise must not be negative");
  if (o.visibility.min_cameras < 1) throw std::invalid_argument("synth: min_cameras must be at least 1");
  if (o.cameras && o.cameras->cameras.empty())
    throw std::invalid_argument("synth: camera rig has no cameras");
}

// Moves a marker site of the base mesh onto the subdivided mesh: the closest point among the
// triangles of the faces its base face was split into.
MarkerSite remap_site(const MarkerSite& site, const DeformedSurface& base, const DeformedSurface& fine,
                      const std::vector<std::vector<int>>& fine_triangles_of_base_face) {
  const int face = base.triangle_face()[static_cast<size_t>(site.triangle)];
  MarkerSite out = site;
  double best = std::numeric_limits<double>::infinity();
  for (int t : fine_triangles_of_base_face[static_cast<size_t>(face)]) {
    const Triangle& tri = fine.triangles()[static_cast<size_t>(t)];
    Vec3 bary;
    const Vec3& a = fine.rest()[static_cast<size_t>(tri[0])];
    const Vec3& b = fine.rest()[static_cast<size_t>(tri[1])];
    const Vec3& c = fine.rest()[static_cast<size_t>(tri[2])];
    const Vec3 q = closest_point_on_triangle(site.rest_position, a, b, c, &bary);
    const double d = (q - site.rest_position).squaredNorm();
    if (d < best) {
      best = d;
      out.triangle = t;
      out.barycentric = bary;
      out.rest_position = q;
      out.rest_normal = triangle_normal(a, b, c);
    }
  }
  return out;
}

std::vector<std::vector<int>> marker_neighbours(const std::vector<MarkerSite>& sites) {
  constexpr int kMax = 6;
  constexpr double kRadius = 80.0;
  std::vector<std::vector<int>> out(sites.size());
  for (size_t i = 0; i < sites.size(); ++i) {
    std::vector<std::pair<double, int>> near;
    for (size_t j = 0; j < sites.size(); ++j) {
      if (i == j) continue;
      const double d = (sites[i].rest_position - sites[j].rest_position).norm();
      if (d < kRadius) near.emplace_back(d, static_cast<int>(j));
    }
    std::sort(near.begin(), near.end());
    for (size_t k = 0; k < near.size() && k < kMax; ++k) out[i].push_back(near[k].second);
  }
  return out;
}

}  // namespace

SynthCapture generate(const Body& body, const SynthOptions& options) {
  validate(body);
  check_options(options);
  const int frames = std::max(1, static_cast<int>(std::lround(options.seconds * options.rate_hz)));
  const Anatomy anatomy = Anatomy::from(body);
  DeformOptions deform = options.deformation;
  if (!options.deform) deform = {0.0, 0.0, 0.0};
  const DeformationModel model(body, anatomy, deform);

  auto scene = std::make_shared<SynthCapture::Scene>();
  scene->skeleton = body.skeleton;
  const DeformedSurface base(body.rest, body.faces, body.weights, model);
  std::vector<int> parent_face;
  if (options.subdivided) {
    Body fine = subdivide(body, &parent_face);
    scene->faces = fine.faces;
    scene->surface = DeformedSurface(std::move(fine.rest), scene->faces, std::move(fine.weights), model);
  } else {
    scene->faces = body.faces;
    scene->surface = base;
  }
  const DeformedSurface& surface = scene->surface;

  // Motion.
  scene->poses.resize(static_cast<size_t>(frames));
  std::vector<BoneTransforms> bones(static_cast<size_t>(frames));
  std::vector<double> breath(static_cast<size_t>(frames)), effort(static_cast<size_t>(frames));
  for (int f = 0; f < frames; ++f) {
    const MotionSample s =
        sample_motion(options.motion, body.skeleton, anatomy, f / options.rate_hz, options.seconds);
    scene->poses[static_cast<size_t>(f)] = s.pose;
    bones[static_cast<size_t>(f)] = pose_bones(body.skeleton, s.pose);
    breath[static_cast<size_t>(f)] = s.breath;
    effort[static_cast<size_t>(f)] = s.effort;
  }
  scene->effects = model.drive(scene->poses, bones, breath, effort, options.rate_hz);

  // Markers.
  LayoutOptions layout = options.layout;
  layout.count = options.markers;
  std::vector<MarkerSite> sites = layout_markers(base.rest(), base.triangles(), base.weights(), body.skeleton,
                                                 anatomy, layout, options.seed);
  if (options.subdivided) {
    std::vector<std::vector<int>> children(body.faces.size());
    for (size_t t = 0; t < surface.triangles().size(); ++t)
      children[static_cast<size_t>(parent_face[static_cast<size_t>(surface.triangle_face()[t])])].push_back(
          static_cast<int>(t));
    for (MarkerSite& s : sites) s = remap_site(s, base, surface, children);
  }
  const int n = static_cast<int>(sites.size());

  SynthCapture out;
  std::vector<std::string> names;
  for (const MarkerSite& s : sites) names.push_back(s.name);
  out.truth = Capture(names, frames, options.rate_hz);
  out.visible.assign(static_cast<size_t>(frames) * static_cast<size_t>(n), 0);
  const CameraRig rig = options.cameras ? *options.cameras : CameraRig::stage12();

  // Per frame: pose the occluding body, place the markers, test them against the cameras.
  Random detection = Random::stream(options.seed, 0xD7EC7u);
  TriangleBvh bvh;
  std::vector<Vec3> posed;
  long occluded = 0;
  for (int f = 0; f < frames; ++f) {
    const BoneTransforms& b = bones[static_cast<size_t>(f)];
    const EffectFrame& e = scene->effects[static_cast<size_t>(f)];
    base.pose(b, e, posed);
    if (f % std::max(1, options.bvh_rebuild_every) == 0)
      bvh = TriangleBvh(posed, base.triangles());
    else
      bvh.refit(posed);
    for (int i = 0; i < n; ++i) {
      const MarkerSite& s = sites[static_cast<size_t>(i)];
      const Triangle& tri = surface.triangles()[static_cast<size_t>(s.triangle)];
      Vec3 c[3];
      for (int k = 0; k < 3; ++k)
        c[k] = options.subdivided ? surface.vertex(tri[static_cast<size_t>(k)], b, e)
                                  : posed[static_cast<size_t>(tri[static_cast<size_t>(k)])];
      const Vec3 normal = triangle_normal(c[0], c[1], c[2]);
      const Vec3 marker = s.barycentric[0] * c[0] + s.barycentric[1] * c[1] + s.barycentric[2] * c[2] +
                          options.marker_offset_mm * normal;
      out.truth.at(f, i) = marker;
      const bool seen = reconstructed(rig, bvh, marker, normal, options.visibility, &detection);
      out.visible[static_cast<size_t>(f) * n + i] = seen ? 1 : 0;
      if (!seen) ++occluded;
    }
  }

  out.markers = sites;
  out.neighbours = marker_neighbours(sites);
  Random rng = Random::stream(options.seed, 0xB8EA4u);
  BrokenCapture broken = break_trajectories(out.truth, out.visible, out.neighbours, options.breaking, rng);
  out.capture = std::move(broken.capture);
  out.source = std::move(broken.source);

  SynthCounts& c = out.counts;
  c.markers = n;
  c.frames = frames;
  c.trajectories_before_merging = broken.counts.trajectories;
  c.labelled_fragments = broken.counts.labelled_fragments;
  c.unlabelled_fragments = broken.counts.unlabelled_fragments;
  c.wrong_label_fragments = broken.counts.wrong_label_fragments;
  c.ghost_trajectories = broken.counts.ghost_trajectories;
  c.ghost_points = broken.counts.ghost_samples;
  c.holes = broken.counts.holes;
  c.gaps = broken.counts.gaps;
  c.occluded_fraction = static_cast<double>(occluded) / (static_cast<double>(frames) * n);
  c.missing_fraction = broken.counts.missing_fraction;
  out.scene_ = std::move(scene);
  return out;
}

std::vector<std::pair<std::string, double>> counts_table(const SynthCounts& c) {
  return {{"markers", c.markers},
          {"frames", c.frames},
          {"trajectories_before_merging", c.trajectories_before_merging},
          {"labelled_fragments", c.labelled_fragments},
          {"unlabelled_fragments", c.unlabelled_fragments},
          {"wrong_label_fragments", c.wrong_label_fragments},
          {"ghost_trajectories", c.ghost_trajectories},
          {"ghost_points", c.ghost_points},
          {"holes", static_cast<double>(c.holes)},
          {"gaps", c.gaps},
          {"occluded_fraction", c.occluded_fraction},
          {"missing_fraction", c.missing_fraction}};
}

}  // namespace skinstream::synth
