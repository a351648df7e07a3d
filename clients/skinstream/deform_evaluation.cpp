#include "clients/skinstream/deform_evaluation.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "clients/skinstream/json_output.h"
#include "clients/skinstream/part_file.h"
#include "core/deform/mesh_deformer.h"
#include "core/geometry/triangle_mesh.h"
#include "core/offline/subject_builder.h"
#include "core/render/software_rasterizer.h"
#include "core/synth/subdivision.h"
#include "protocol/research/png_file.h"

namespace skinstream::cli {
namespace {

using synth::SynthCapture;

// Which skin weights a conventional (sparse-marker LBS) row uses; None: a part-based method.
enum class Skinning { None, BoneHeat, TruthOracle };

struct DeformMethod {
  const char* name;
  const char* caption;
  Skinning skinning;
  DeformationMode mode;
};
constexpr DeformMethod kMethods[] = {
    {"rigid", "rigid", Skinning::None, DeformationMode::Rigid},
    {"quadratic", "quadratic", Skinning::None, DeformationMode::Quadratic},
    {"rigid_rbf", "rigid+rbf", Skinning::None, DeformationMode::RigidRbf},
    {"full", "full", Skinning::None, DeformationMode::QuadraticRbf},
    {"lbs_bone_heat", "lbs heat", Skinning::BoneHeat, DeformationMode::Rigid},
    {"lbs_truth_weights", "lbs oracle", Skinning::TruthOracle, DeformationMode::Rigid},
};
constexpr double kHeatMaxMm = 20.0;  // the render's colour scale: blue 0 .. red 20 mm

// Where a marker sits on the registered mesh: its closest point in the reference pose
// (triangle and barycentric coordinates) and its height above the surface along the normal.
struct MarkerSiteOnMesh {
  int triangle = -1;
  Vec3 barycentric = Vec3::Zero();
  double height = 0.0;
};

std::vector<MarkerSiteOnMesh> locate_markers(const std::vector<Vec3>& vertices,
                                             const std::vector<std::array<int, 3>>& faces,
                                             const std::vector<Vec3>& markers) {
  std::vector<MarkerSiteOnMesh> sites(markers.size());
  for (size_t m = 0; m < markers.size(); ++m) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t f = 0; f < faces.size(); ++f) {
      const auto& t = faces[f];
      Vec3 bary;
      const Vec3 p = closest_point_on_triangle(markers[m], vertices[t[0]], vertices[t[1]], vertices[t[2]], &bary);
      const double d = (p - markers[m]).squaredNorm();
      if (d < best) {
        best = d;
        sites[m].triangle = static_cast<int>(f);
        sites[m].barycentric = bary;
        sites[m].height =
            (markers[m] - p).dot(triangle_normal(vertices[t[0]], vertices[t[1]], vertices[t[2]]));
      }
    }
  }
  return sites;
}

Vec3 vertex_at(const std::vector<float>& positions, int v) {
  return Vec3(positions[static_cast<size_t>(v) * 3], positions[static_cast<size_t>(v) * 3 + 1],
              positions[static_cast<size_t>(v) * 3 + 2]);
}

Vec3 site_position(const std::vector<float>& positions, const std::vector<std::array<int, 3>>& faces,
                   const MarkerSiteOnMesh& site) {
  const auto& t = faces[site.triangle];
  const Vec3 a = vertex_at(positions, t[0]), b = vertex_at(positions, t[1]), c = vertex_at(positions, t[2]);
  const Vec3 on_surface = site.barycentric[0] * a + site.barycentric[1] * b + site.barycentric[2] * c;
  return on_surface + site.height * triangle_normal(a, b, c);
}

// Vertices the markers cover: within `reach` of the reference marker surface. The dense set has
// no markers on the head, hands and feet; no marker-driven method can know how those move.
std::vector<char> covered_vertices(const DeformationModel& model, const SubjectModel& subject, double reach) {
  std::vector<char> covered(model.vertex_count(), 0);
  for (int v = 0; v < model.vertex_count(); ++v) {
    const Vec3& p = model.reference_vertices[v];
    for (const auto& t : subject.triangles) {
      const Vec3 q = closest_point_on_triangle(p, subject.reference_positions[t[0]],
                                                      subject.reference_positions[t[1]], subject.reference_positions[t[2]]);
      if ((q - p).squaredNorm() <= reach * reach) {
        covered[v] = 1;
        break;
      }
    }
  }
  return covered;
}

std::vector<Vec3> markers_in_subject_order(const SynthCapture& take, const std::vector<int>& subject_to_truth, int frame) {
  std::vector<Vec3> markers(subject_to_truth.size());
  for (size_t i = 0; i < markers.size(); ++i) markers[i] = take.truth.at(frame, subject_to_truth[i]);
  return markers;
}

// Where a method's maximum comes from: the covered vertices with the largest error over the take,
// with how far each lies from the nearest marker in the reference pose (a crease no marker reaches
// shows here) and, for the part-based methods, the parts that move it (beta_{j,p}) and the part
// that alone would have placed it best at that frame. A best part far below the error means the
// vertex weights sent it with the wrong parts; a best part as far off means no part's motion fits.
// `deformer` is the method's (refitted here at each vertex's frame), null for one without parts.
nlohmann::ordered_json worst_vertices(const std::vector<double>& peak_error, const std::vector<int>& peak_frame,
                                      const std::vector<char>& covered, const DeformationSetup& setup,
                                      const SynthCapture& take, MeshDeformer* deformer, int count) {
  const DeformationModel& model = setup.deformation;
  const SubjectModel& subject = setup.subject;
  std::vector<int> order;
  for (int v = 0; v < static_cast<int>(covered.size()); ++v)
    if (covered[v]) order.push_back(v);
  count = std::min<int>(count, static_cast<int>(order.size()));
  std::partial_sort(order.begin(), order.begin() + count, order.end(),
                    [&](int a, int b) { return peak_error[a] > peak_error[b]; });
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  for (int i = 0; i < count; ++i) {
    const int v = order[i];
    const Vec3& at = model.reference_vertices[v];
    double nearest = std::numeric_limits<double>::infinity();
    for (const Vec3& m : subject.reference_positions) nearest = std::min(nearest, (m - at).norm());
    int nearest_marker = 0;
    for (int m = 0; m < subject.marker_count(); ++m)
      if ((subject.reference_positions[m] - at).norm() < (subject.reference_positions[nearest_marker] - at).norm())
        nearest_marker = m;
    nlohmann::ordered_json row = {{"vertex", v},
                                  {"error_mm", peak_error[v]},
                                  {"frame", peak_frame[v]},
                                  {"reference_mm", {at.x(), at.y(), at.z()}},
                                  {"nearest_marker", subject.marker_names[nearest_marker]},
                                  {"nearest_marker_mm", nearest}};
    if (deformer) {
      row["parts"] = nlohmann::ordered_json::array();
      for (int k = model.vertex_influence_offsets[v]; k < model.vertex_influence_offsets[v + 1]; ++k)
        row["parts"].push_back({{"part", model.vertex_influences[k].part}, {"weight", model.vertex_influences[k].weight}});
      deformer->solve_parts(markers_in_subject_order(take, setup.subject_to_truth, peak_frame[v]));
      const Vec3 truth = take.pose_mesh(peak_frame[v])[v];
      int best = 0;
      double best_error = std::numeric_limits<double>::infinity();
      for (int p = 0; p < model.part_count(); ++p) {
        const PartDeformer& part = deformer->part(p);
        const double e = (part.deform(part.model().local_from_world(at)) - truth).norm();
        if (e < best_error) best = p, best_error = e;
      }
      row["best_single_part"] = {{"part", best}, {"error_mm", best_error}};
    }
    out.push_back(row);
  }
  return out;
}

}  // namespace

DeformationSetup prepare_deformation(const Body& body, const SynthCapture& training,
                                     const DeformEvaluationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  DeformationSetup setup;
  SubjectBuildReport subject_report;
  setup.subject = build_subject(training.truth, SubjectBuildOptions{}, nullptr, &subject_report);
  const int n = setup.subject.marker_count();
  for (int i = 0; i < n; ++i) {
    const auto& labels = training.truth.labels;
    const auto it = std::find(labels.begin(), labels.end(), setup.subject.marker_names[i]);
    if (it == labels.end()) throw std::logic_error("subject marker missing from the truth: " + setup.subject.marker_names[i]);
    setup.subject_to_truth.push_back(static_cast<int>(it - labels.begin()));
  }
  std::vector<Vec3> positions(static_cast<size_t>(training.frame_count()) * n);
  for (int f = 0; f < training.frame_count(); ++f)
    for (int i = 0; i < n; ++i) positions[static_cast<size_t>(f) * n + i] = training.truth.at(f, setup.subject_to_truth[i]);

  // The artist's model: the subject's skin in the reference pose, without the frame's bulges,
  // breathing and jiggle; registration pulls it onto the markers. Landmarks: the mesh vertex
  // each marker was placed at.
  const std::vector<Vec3> artist_mesh = training.pose_mesh(subject_report.reference_frame, /*skin_only=*/true);
  const auto& faces = training.mesh_triangles();
  DeformationBuildOptions build;
  build.registration.marker_offset_mm = options.marker_offset_mm;
  for (int i = 0; i < n; ++i) {
    const synth::MarkerSite& site = training.markers[setup.subject_to_truth[i]];
    int corner = 0;
    site.barycentric.maxCoeff(&corner);
    build.landmarks.push_back({i, faces[site.triangle][corner]});
  }
  const std::vector<Vec3> truth_skin = training.pose_mesh(subject_report.reference_frame);
  const std::vector<Vec3> registered = register_mesh(artist_mesh, faces, setup.subject.reference_positions,
                                                     build.landmarks, build.registration, &setup.registration);
  for (size_t v = 0; v < registered.size(); ++v)
    setup.registration_vertex_error_mm += (registered[v] - truth_skin[v]).norm() / static_cast<double>(registered.size());
  build.register_mesh = false;
  apply_weight_rules(options.weight_rules, build);
  if (!options.part_file.empty()) {
    build.part_assignment = read_part_file(options.part_file, setup.subject);
    build.assignment_kind = AssignmentKind::PerMarker;
  }
  setup.deformation = build_deformation_model(setup.subject, positions, training.frame_count(),
                                              options.deform_registered_mesh ? registered : truth_skin, faces, build,
                                              &setup.build);

  const Body skinned = training.mesh_vertex_count() == body.vertex_count() ? body : synth::subdivide(body);
  setup.conventional = synth::choose_conventional_markers(body, training, skinned.weights);
  // Its markers in subject order.
  for (auto& segment : setup.conventional.skinning.segment_markers)
    for (int& m : segment)
      m = static_cast<int>(std::find(setup.subject_to_truth.begin(), setup.subject_to_truth.end(), m) -
                           setup.subject_to_truth.begin());
  setup.conventional_heat = synth::bone_heat_skinning(skinned, setup.conventional);
  setup.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return setup;
}

nlohmann::ordered_json evaluate_deformation(const DeformationSetup& setup, const SynthCapture& take,
                                            const std::string& motion, const DeformEvaluationOptions& options) {
  const DeformationModel& model = setup.deformation;
  const int vertices = model.vertex_count();
  if (take.mesh_vertex_count() != vertices)
    throw std::invalid_argument("the take's mesh has " + std::to_string(take.mesh_vertex_count()) +
                                " vertices, the subject's " + std::to_string(vertices));
  const std::vector<MarkerSiteOnMesh> sites =
      locate_markers(model.reference_vertices, model.faces, setup.subject.reference_positions);

  const int method_count = static_cast<int>(std::size(kMethods));
  std::vector<std::unique_ptr<MeshDeformer>> deformers;
  std::vector<std::unique_ptr<SegmentSkinning>> skinnings;
  for (const DeformMethod& m : kMethods) {
    const bool parts = m.skinning == Skinning::None;
    deformers.push_back(parts ? std::make_unique<MeshDeformer>(model, setup.subject, m.mode) : nullptr);
    skinnings.push_back(parts ? nullptr
                              : std::make_unique<SegmentSkinning>(m.skinning == Skinning::TruthOracle
                                                                      ? setup.conventional.skinning
                                                                      : setup.conventional_heat,
                                                                  setup.subject.reference_positions,
                                                                  model.reference_vertices));
  }

  const std::vector<char> covered = covered_vertices(model, setup.subject, options.covered_reach_mm);
  int covered_count = 0;
  for (char c : covered) covered_count += c;
  std::vector<std::vector<double>> vertex_errors(method_count), all_vertex_errors(method_count), marker_errors(method_count);
  std::vector<double> seconds(method_count, 0.0);
  // Per method and vertex: its largest error over the take, and the frame.
  std::vector<std::vector<double>> peak_error(method_count, std::vector<double>(vertices, 0.0));
  std::vector<std::vector<int>> peak_frame(method_count, std::vector<int>(vertices, 0));
  std::vector<float> positions(static_cast<size_t>(vertices) * 3);
  int frames = 0;
  for (int f = 0; f < take.frame_count(); f += options.frame_stride, ++frames) {
    const std::vector<Vec3> markers = markers_in_subject_order(take, setup.subject_to_truth, f);
    const std::vector<Vec3> truth = take.pose_mesh(f);
    for (int k = 0; k < method_count; ++k) {
      const auto start = std::chrono::steady_clock::now();
      if (skinnings[k]) {
        if (!skinnings[k]->solve(markers)) throw std::logic_error("conventional markers missing from the truth");
        skinnings[k]->deform(positions);
      } else if (!deformers[k]->deform(markers, positions, {})) {
        throw std::logic_error("markers missing from the truth");
      }
      seconds[k] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      for (int v = 0; v < vertices; ++v) {
        const double e = (vertex_at(positions, v) - truth[v]).norm();
        all_vertex_errors[k].push_back(e);
        if (covered[v]) vertex_errors[k].push_back(e);
        if (e > peak_error[k][v]) peak_error[k][v] = e, peak_frame[k][v] = f;
      }
      for (size_t i = 0; i < sites.size(); ++i)
        marker_errors[k].push_back((site_position(positions, model.faces, sites[i]) - markers[i]).norm());
    }
  }

  // A few frames drawn side by side: the truth, then every method coloured by its vertex error.
  std::vector<std::string> rendered;
  if (!options.render_dir.empty()) {
    std::filesystem::create_directories(options.render_dir);
    for (int r = 1; r <= options.render_frames; ++r) {
      const int f = r * (take.frame_count() - 1) / (options.render_frames + 1);
      const std::vector<Vec3> markers = markers_in_subject_order(take, setup.subject_to_truth, f);
      const std::vector<Vec3> truth = take.pose_mesh(f);
      const render::Camera camera = render::frame_view(truth, render::View::front, 300, 480);
      std::vector<render::Image> images;
      std::vector<std::string> captions = {"truth"};
      render::RenderMesh truth_mesh;
      truth_mesh.vertices = truth;
      truth_mesh.faces = model.faces;
      images.push_back(render::render_mesh(truth_mesh, camera));
      for (int k = 0; k < method_count; ++k) {
        if (skinnings[k]) {
          skinnings[k]->solve(markers);
          skinnings[k]->deform(positions);
        } else {
          deformers[k]->deform(markers, positions, {});
        }
        std::vector<Vec3> mesh(vertices);
        std::vector<double> error(vertices);
        for (int v = 0; v < vertices; ++v) {
          mesh[v] = vertex_at(positions, v);
          error[v] = (mesh[v] - truth[v]).norm();
        }
        const std::vector<render::Rgb> colours = render::heat_colours(error, kHeatMaxMm);
        render::RenderMesh view;
        view.vertices = mesh;
        view.faces = model.faces;
        view.colours = colours;
        images.push_back(render::render_mesh(view, camera));
        captions.push_back(kMethods[k].caption);
      }
      char name[96];
      std::snprintf(name, sizeof name, "%s_frame%04d.png", motion.c_str(), f);
      const std::string path = (std::filesystem::path(options.render_dir) / name).string();
      write_png(path, render::compose_side_by_side(images, captions));
      rendered.push_back(path);
    }
  }

  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (int k = 0; k < method_count; ++k) {
    const ErrorStats v = summarize_errors(std::move(vertex_errors[k]));
    const ErrorStats m = summarize_errors(std::move(marker_errors[k]));
    const ErrorStats all = summarize_errors(std::move(all_vertex_errors[k]));
    rows.push_back({{"method", kMethods[k].name},
                    {"oracle", kMethods[k].skinning == Skinning::TruthOracle},
                    {"vertex_mean_mm", v.mean},
                    {"vertex_p95_mm", v.p95},
                    {"vertex_max_mm", v.max},
                    {"all_vertex_mean_mm", all.mean},
                    {"all_vertex_max_mm", all.max},
                    {"marker_mean_mm", m.mean},
                    {"marker_max_mm", m.max},
                    {"ms_per_frame_single_thread", 1000.0 * seconds[k] / frames},
                    {"worst_vertices", worst_vertices(peak_error[k], peak_frame[k], covered, setup, take, deformers[k].get(), 3)}});
  }
  return {{"motion", motion},
          {"frames_evaluated", frames},
          {"vertices", vertices},
          {"covered_vertices", covered_count},
          {"renders", rendered},
          {"methods", rows}};
}

nlohmann::ordered_json judge_table_rule(const nlohmann::ordered_json& takes) {
  int met = 0;
  nlohmann::ordered_json misses = nlohmann::ordered_json::array(), maxima = nlohmann::ordered_json::array();
  for (const auto& take : takes) {
    const nlohmann::ordered_json* full = nullptr;
    const nlohmann::ordered_json* lowest_max = nullptr;
    for (const auto& row : take["methods"]) {
      if (row["method"] == "full") full = &row;
      if (!lowest_max || row["vertex_max_mm"].get<double>() < (*lowest_max)["vertex_max_mm"].get<double>()) lowest_max = &row;
    }
    if (!full) throw std::logic_error("judge_table_rule: a take without the full method");
    bool lowest = true;
    for (const auto& row : take["methods"]) {
      if (&row == full || row["oracle"].get<bool>()) continue;
      for (const char* column : {"vertex_mean_mm", "vertex_p95_mm"})
        if ((*full)[column].get<double>() >= row[column].get<double>()) {
          lowest = false;
          misses.push_back({{"motion", take["motion"]}, {"column", column}, {"by", row["method"]},
                            {"full", (*full)[column]}, {"theirs", row[column]}});
        }
    }
    met += lowest;
    const auto& worst = (*full)["worst_vertices"][0];
    maxima.push_back({{"motion", take["motion"]},
                      {"lowest", (*lowest_max)["method"]},
                      {"lowest_mm", (*lowest_max)["vertex_max_mm"]},
                      {"full_mm", (*full)["vertex_max_mm"]},
                      {"full_at", {{"vertex", worst["vertex"]}, {"frame", worst["frame"]},
                                   {"nearest_marker", worst["nearest_marker"]}}}});
  }
  return {{"rule", "full method: lowest vertex mean and p95 against every non-oracle row"},
          {"takes", takes.size()},
          {"met", met},
          {"misses", misses},
          {"maxima", maxima}};
}

}  // namespace skinstream::cli
