#include "core/deform/evaluation_model.h"

#include <cmath>
#include <sstream>


namespace skinstream {

int EvaluationModel::first_member(int part) const {
  int first = 0;
  for (int p = 0; p < part; ++p) first += parts[p].member_count;
  return first;
}

namespace {

template <size_t N>
bool all_finite(const std::array<float, N>& values) {
  for (float v : values)
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace

std::string EvaluationModel::validate() const {
  std::ostringstream out;
  if (reference_vertices.empty() || reference_vertices.size() % 3 != 0)
    return "evaluation model: " + std::to_string(reference_vertices.size()) + " vertex coordinates (not a positive multiple of 3)";
  const int n = vertex_count();
  for (size_t i = 0; i < reference_vertices.size(); ++i)
    if (!std::isfinite(reference_vertices[i])) {
      out << "evaluation model: vertex " << i / 3 << " is not finite";
      return out.str();
    }
  for (size_t f = 0; f < faces.size(); ++f)
    for (int c : faces[f])
      if (c < 0 || c >= n) {
        out << "evaluation model: face " << f << " refers to vertex " << c << " of " << n;
        return out.str();
      }
  if (parts.empty()) return "evaluation model: no parts";
  long members = 0;
  for (size_t p = 0; p < parts.size(); ++p) {
    const EvaluationPart& part = parts[p];
    if (part.member_count < 1) {
      out << "evaluation model: part " << p << " has no members";
      return out.str();
    }
    members += part.member_count;
    if (!all_finite(part.rotation) || !all_finite(part.translation) || !all_finite(part.box_min) ||
        !all_finite(part.box_max) || !std::isfinite(part.sigma) || part.sigma < 0.0f) {
      out << "evaluation model: part " << p << " has a value that is not finite (or a negative dilation)";
      return out.str();
    }
    for (int a = 0; a < 3; ++a)
      if (part.box_min[a] > part.box_max[a]) {
        out << "evaluation model: part " << p << "'s box is empty on axis " << a;
        return out.str();
      }
    // R^0 must be a rotation: the evaluation takes its transpose as its inverse.
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        double dot = 0.0;
        for (int k = 0; k < 3; ++k) dot += double(part.rotation[3 * r + k]) * part.rotation[3 * c + k];
        if (std::abs(dot - (r == c ? 1.0 : 0.0)) > 1e-4) {
          out << "evaluation model: part " << p << "'s reference rotation is not orthonormal";
          return out.str();
        }
      }
  }
  if (members != member_count()) {
    out << "evaluation model: the parts count " << members << " members, the model holds " << member_count();
    return out.str();
  }
  for (float v : member_reference)
    if (!std::isfinite(v)) return "evaluation model: a member's reference position is not finite";
  if (influence_offsets.size() != static_cast<size_t>(n) + 1 || influence_offsets.front() != 0 ||
      influence_offsets.back() != influence_count() || influence_weights.size() != influence_parts.size()) {
    out << "evaluation model: " << influence_offsets.size() << " influence offsets and " << influence_parts.size() << " parts, "
        << influence_weights.size() << " weights for " << n << " vertices";
    return out.str();
  }
  for (int v = 0; v < n; ++v) {
    if (influence_offsets[v + 1] <= influence_offsets[v]) {
      out << "evaluation model: vertex " << v << " has no influence";
      return out.str();
    }
    double sum = 0.0;
    for (int k = influence_offsets[v]; k < influence_offsets[v + 1]; ++k) {
      if (influence_parts[k] < 0 || influence_parts[k] >= part_count()) {
        out << "evaluation model: vertex " << v << " is influenced by part " << influence_parts[k] << " of " << part_count();
        return out.str();
      }
      if (!std::isfinite(influence_weights[k]) || influence_weights[k] < 0.0f) {
        out << "evaluation model: vertex " << v << " has a negative or non-finite weight";
        return out.str();
      }
      sum += influence_weights[k];
    }
    if (std::abs(sum - 1.0) > 1e-3) {
      out << "evaluation model: vertex " << v << "'s weights sum to " << sum << ", not 1";
      return out.str();
    }
  }
  return {};
}

}  // namespace skinstream
