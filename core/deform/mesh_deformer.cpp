#include "core/deform/mesh_deformer.h"

#include <stdexcept>

#include "core/deform/part_model.h"
#include "core/deform/skeleton_solver.h"

namespace skinstream {

struct MeshDeformer::State {
  DeformationMode mode = DeformationMode::QuadraticRbf;
  int marker_count = 0;
  std::vector<PartDeformer> parts;
  std::vector<int> member_offsets;  // CSR over parts into member_markers
  std::vector<int> member_markers;
  std::vector<Vec3> member_scratch;
  // A model fitted by its skeleton: the pose each frame, and each part's segment.
  std::unique_ptr<SkeletonSolver> skeleton;
  std::vector<int> part_segment;
  EvaluationModel evaluation_model;
  std::unique_ptr<MeshEvaluator> evaluator;
  FrameParameters parameters;

  void store_parameters(int p);
};

namespace {

std::vector<PartModel> part_models(const DeformationModel& model, const SubjectModel& subject) {
  std::vector<PartModel> parts;
  for (int p = 0; p < model.part_count(); ++p) {
    std::vector<Vec3> reference;
    for (int k = model.part_member_offsets[p]; k < model.part_member_offsets[p + 1]; ++k)
      reference.push_back(subject.reference_positions[model.part_members[k].marker]);
    PartModel part = build_part_model(reference, model.part_quadratic_ridge.empty() ? 0.0 : model.part_quadratic_ridge[p]);
    if (!model.part_rbf_ridge.empty()) part.rbf_ridge = model.part_rbf_ridge[p];
    if (!model.part_quadratic.empty()) part.quadratic = model.part_quadratic[p] != 0;
    parts.push_back(std::move(part));
  }
  return parts;
}

}  // namespace

EvaluationModel make_evaluation_model(const DeformationModel& model, const std::vector<PartModel>& part_models) {
  EvaluationModel out;
  out.reference_vertices.reserve(3 * model.reference_vertices.size());
  for (const Vec3& v : model.reference_vertices)
    for (int a = 0; a < 3; ++a) out.reference_vertices.push_back(static_cast<float>(v[a]));
  out.faces = model.faces;
  for (const PartModel& part : part_models) {
    EvaluationPart e;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) e.rotation[3 * r + c] = static_cast<float>(part.reference_frame.rotation(r, c));
      e.translation[r] = static_cast<float>(part.reference_frame.translation[r]);
      e.box_min[r] = static_cast<float>(part.local_min[r]);
      e.box_max[r] = static_cast<float>(part.local_max[r]);
    }
    e.sigma = static_cast<float>(part.rbf_dilation);
    e.member_count = part.member_count();
    out.parts.push_back(e);
    for (const Vec3& p : part.local_reference_points)
      for (int a = 0; a < 3; ++a) out.member_reference.push_back(static_cast<float>(p[a]));
  }
  out.influence_offsets = model.vertex_influence_offsets;
  for (const PartInfluence& influence : model.vertex_influences) {
    out.influence_parts.push_back(influence.part);
    out.influence_weights.push_back(static_cast<float>(influence.weight));
  }
  return out;
}

MeshDeformer::MeshDeformer(const DeformationModel& model, const SubjectModel& subject, DeformationMode mode)
    : state_(std::make_unique<State>()) {
  const std::string problem = model.validate(subject.marker_count());
  if (!problem.empty()) throw std::invalid_argument(problem);
  State& s = *state_;
  s.mode = mode;
  s.marker_count = subject.marker_count();
  // Parts: the local part reference frames and the offline factors of eqs. 6-7, from the member
  // markers' reference positions (the reference pose is every part's rest state).
  std::vector<PartModel> parts = part_models(model, subject);
  s.evaluation_model = make_evaluation_model(model, parts);
  s.evaluator = std::make_unique<MeshEvaluator>(s.evaluation_model);
  s.parameters = rest_parameters(s.evaluation_model);
  s.member_offsets = model.part_member_offsets;
  for (const PartMember& member : model.part_members) s.member_markers.push_back(member.marker);
  s.member_scratch.resize(s.member_markers.size());
  s.parts.reserve(parts.size());
  for (PartModel& part : parts) s.parts.emplace_back(std::move(part), mode);
  if (!model.skeleton.empty()) {
    s.skeleton = std::make_unique<SkeletonSolver>(model.skeleton, subject.reference_positions);
    s.part_segment = model.skeleton.part_segment;
  }
}

MeshDeformer::~MeshDeformer() = default;

// The part's fit in float, as the evaluator takes it (and the subscriber protocol sends it).
void MeshDeformer::State::store_parameters(int p) {
  const PartDeformer& part = parts[p];
  PartParameters& out = parameters.parts[p];
  const QuadraticTransform& a = part.quadratic_transform();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 9; ++c) out.quadratic[9 * r + c] = static_cast<float>(a(r, c));
  const RigidTransform& to_local = part.to_local();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.rotation[3 * r + c] = static_cast<float>(to_local.rotation(r, c));
    out.translation[r] = static_cast<float>(to_local.translation[r]);
  }
  out.rbf = part.rbf_applied();
  const int first = member_offsets[p], count = member_offsets[p + 1] - first;
  float* weights = parameters.weights.data() + 3 * static_cast<size_t>(first);
  const Eigen::MatrixX3d& w = part.rbf_weights();
  for (int i = 0; i < count; ++i)
    for (int a = 0; a < 3; ++a) weights[3 * i + a] = out.rbf ? static_cast<float>(w(i, a)) : 0.0f;
  evaluator->set_part(p, out, std::span<const float>(weights, 3 * static_cast<size_t>(count)));
}

bool MeshDeformer::accepts(std::span<const Vec3> markers) const {
  if (static_cast<int>(markers.size()) != state_->marker_count) return false;
  for (const Vec3& m : markers)
    if (!is_present(m)) return false;
  return true;
}

void MeshDeformer::solve_part(int p, std::span<const Vec3> markers) {
  State& s = *state_;
  const int begin = s.member_offsets[p], count = s.member_offsets[p + 1] - begin;
  Vec3* members = s.member_scratch.data() + begin;  // each part its own slice: parts may run in parallel
  for (int i = 0; i < count; ++i) members[i] = markers[s.member_markers[begin + i]];
  const std::span<const Vec3> member_span(members, count);
  const bool solved = s.skeleton ? s.parts[p].solve(member_span, s.skeleton->segment_motion(s.part_segment[p]))
                                 : s.parts[p].solve(member_span);
  if (solved) s.store_parameters(p);
}

void MeshDeformer::solve_skeleton(std::span<const Vec3> markers) {
  if (state_->skeleton) state_->skeleton->solve(markers);
}

bool MeshDeformer::has_skeleton() const { return state_->skeleton != nullptr; }

const SkeletonSolver* MeshDeformer::skeleton() const { return state_->skeleton.get(); }

bool MeshDeformer::solve_parts(std::span<const Vec3> markers) {
  if (!accepts(markers)) return false;
  solve_skeleton(markers);
  for (int p = 0; p < part_count(); ++p) solve_part(p, markers);
  return true;
}

const FrameParameters& MeshDeformer::parameters() const { return state_->parameters; }
const EvaluationModel& MeshDeformer::evaluation_model() const { return state_->evaluation_model; }

int MeshDeformer::part_count() const { return static_cast<int>(state_->parts.size()); }
int MeshDeformer::part_member_count(int p) const { return state_->parts[p].model().member_count(); }
int MeshDeformer::cluster_part(int c) const { return state_->evaluator->cluster_part(c); }
bool MeshDeformer::cluster_in_upper_half(int c) const { return state_->evaluator->cluster_in_upper_half(c); }
void MeshDeformer::deform_clusters(int begin, int end) { state_->evaluator->deform_clusters(begin, end); }
int MeshDeformer::cluster_count() const { return state_->evaluator->cluster_count(); }
void MeshDeformer::blend_vertices(int begin, int end, std::span<float> positions) const {
  state_->evaluator->blend_vertices(begin, end, positions);
}
void MeshDeformer::vertex_normals(int begin, int end, std::span<const float> positions, std::span<float> normals) const {
  state_->evaluator->vertex_normals(begin, end, positions, normals);
}

bool MeshDeformer::deform(std::span<const Vec3> markers, std::span<float> positions, std::span<float> normals) {
  if (!solve_parts(markers)) return false;
  deform_clusters(0, cluster_count());
  blend_vertices(0, vertex_count(), positions);
  if (!normals.empty()) vertex_normals(0, vertex_count(), positions, normals);
  return true;
}

int MeshDeformer::vertex_count() const { return state_->evaluator->vertex_count(); }
int MeshDeformer::sequence_vertex(int slot) const { return state_->evaluator->sequence_vertex(slot); }
int MeshDeformer::upper_half_slot() const { return state_->evaluator->upper_half_slot(); }
int MeshDeformer::normal_group_size() const { return state_->evaluator->normal_group_size(); }
DeformationMode MeshDeformer::mode() const { return state_->mode; }
const PartDeformer& MeshDeformer::part(int part) const { return state_->parts.at(static_cast<size_t>(part)); }

size_t MeshDeformer::memory_bytes() const {
  const State& s = *state_;
  auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  size_t total = sizeof(State) + s.evaluator->memory_bytes() + bytes(s.member_offsets) + bytes(s.member_markers) +
                 bytes(s.member_scratch) + bytes(s.parameters.parts) + bytes(s.parameters.weights);
  for (const PartDeformer& part : s.parts) {
    const int y = part.model().member_count();
    // Members' reference data (points, Q0, pseudo-inverse), the per-frame centres (twice),
    // positions, residuals and weights, the kernel (factored in place by LLT) and its LU.
    total += sizeof(PartDeformer) + static_cast<size_t>(y) * (3 + 3 + 9 + 9 + 3 + 3 + 3 + 3 + 3) * sizeof(double) +
             2 * static_cast<size_t>(y) * y * sizeof(double);
  }
  return total;
}

}  // namespace skinstream
