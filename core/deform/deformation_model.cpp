#include "core/deform/deformation_model.h"

#include <cmath>
#include <sstream>

namespace skinstream {

int DeformationModel::dominant_part(int vertex) const {
  int best = -1;
  double best_weight = -1.0;
  for (int k = vertex_influence_offsets[vertex]; k < vertex_influence_offsets[vertex + 1]; ++k) {
    if (vertex_influences[k].weight > best_weight) {
      best_weight = vertex_influences[k].weight;
      best = vertex_influences[k].part;
    }
  }
  return best;
}

namespace {

bool finite(const Vec3& p) { return p.allFinite(); }

std::string check_csr(const std::vector<int>& offsets, size_t rows, size_t entries, const char* what) {
  std::ostringstream out;
  if (offsets.size() != rows + 1) {
    out << what << ": " << offsets.size() << " offsets for " << rows << " rows";
    return out.str();
  }
  if (offsets.front() != 0 || static_cast<size_t>(offsets.back()) != entries) {
    out << what << ": offsets do not span the " << entries << " entries";
    return out.str();
  }
  for (size_t i = 0; i + 1 < offsets.size(); ++i) {
    if (offsets[i] > offsets[i + 1]) {
      out << what << ": offsets decrease at row " << i;
      return out.str();
    }
  }
  return {};
}

}  // namespace

std::string DeformationModel::validate(int marker_count) const {
  std::ostringstream out;
  const int n = vertex_count();
  if (n == 0) return "deformation model: no vertices";
  for (int v = 0; v < n; ++v) {
    if (!finite(reference_vertices[v])) {
      out << "deformation model: vertex " << v << " is not finite";
      return out.str();
    }
  }
  for (size_t f = 0; f < faces.size(); ++f) {
    for (int c : faces[f]) {
      if (c < 0 || c >= n) {
        out << "deformation model: face " << f << " refers to vertex " << c << " of " << n;
        return out.str();
      }
    }
  }
  if (part_names.empty()) return "deformation model: no parts";
  if (auto e = check_csr(part_member_offsets, part_names.size(), part_members.size(), "part members"); !e.empty()) return "deformation model: " + e;
  for (int p = 0; p < part_count(); ++p) {
    if (part_member_offsets[p] == part_member_offsets[p + 1]) {
      out << "deformation model: part " << p << " (" << part_names[p] << ") has no markers";
      return out.str();
    }
  }
  for (const PartMember& m : part_members) {
    if (m.marker < 0 || m.marker >= marker_count || !(m.weight > 0.0 && m.weight <= 1.0 + 1e-9)) {
      out << "deformation model: part member marker " << m.marker << " weight " << m.weight
          << " invalid for " << marker_count << " markers";
      return out.str();
    }
  }
  // Per-part ridges: none (an older subject file), or one per part within [0, largest].
  auto check_ridges = [&](const std::vector<double>& ridges, const char* what, double largest) {
    if (!ridges.empty() && ridges.size() != part_names.size()) {
      out << "deformation model: " << ridges.size() << " " << what << "s for " << part_count() << " parts";
      return false;
    }
    for (size_t p = 0; p < ridges.size(); ++p) {
      if (!(ridges[p] >= 0.0 && ridges[p] <= largest)) {
        out << "deformation model: part " << p << " has " << what << " " << ridges[p] << " (0 to " << largest << ")";
        return false;
      }
    }
    return true;
  };
  if (!check_ridges(part_rbf_ridge, "ridge", 1e3) || !check_ridges(part_quadratic_ridge, "quadratic ridge", 1e4))
    return out.str();
  if (!skeleton.empty()) {
    if (const std::string e = skeleton.validate(marker_count, part_count()); !e.empty()) return "deformation model: " + e;
  }
  if (!part_quadratic.empty() && part_quadratic.size() != part_names.size()) {
    out << "deformation model: " << part_quadratic.size() << " quadratic flags for " << part_count() << " parts";
    return out.str();
  }
  if (!rest_vertices.empty() && rest_vertices.size() != reference_vertices.size()) {
    out << "deformation model: " << rest_vertices.size() << " rest vertices for " << n << " vertices";
    return out.str();
  }
  for (const Vec3& v : rest_vertices)
    if (!finite(v)) return "deformation model: a rest vertex is not finite";
  if (auto e = check_csr(vertex_influence_offsets, reference_vertices.size(), vertex_influences.size(), "vertex influences"); !e.empty()) return "deformation model: " + e;
  for (int v = 0; v < n; ++v) {
    double sum = 0.0;
    for (int k = vertex_influence_offsets[v]; k < vertex_influence_offsets[v + 1]; ++k) {
      const PartInfluence& inf = vertex_influences[k];
      if (inf.part < 0 || inf.part >= part_count() || !(inf.weight >= 0.0)) {
        out << "deformation model: vertex " << v << " has an invalid part influence";
        return out.str();
      }
      sum += inf.weight;
    }
    if (std::abs(sum - 1.0) > 1e-6) {
      out << "deformation model: vertex " << v << " weights sum to " << sum << ", not 1";
      return out.str();
    }
  }
  return {};
}

}  // namespace skinstream
