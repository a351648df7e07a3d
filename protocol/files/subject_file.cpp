#include "protocol/files/subject_file.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <unordered_set>

#include "protocol/byte_buffer.h"
#include "protocol/byte_reader.h"
#include "protocol/files/file_error.h"
#include "protocol/printable_text.h"

namespace skinstream {
namespace {

constexpr char kMagic[8] = {'S', 'K', 'S', 'U', 'B', 'J', '\r', '\n'};

// A payload whose values do not make sense (a read past its end is the reader's ByteError);
// thrown only while the reader is ok(), so the first problem is the one reported.
struct SubjectPayloadError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A u32 length + bytes of at most max_length; empty once the reader failed.
std::string get_string(ByteReader& r, size_t max_length, const char* what) {
  const uint32_t n = r.get<uint32_t>(what);
  if (n > max_length) throw SubjectPayloadError("string of " + std::to_string(n) + " bytes is implausible");
  const std::span<const unsigned char> bytes = r.take(n, what);
  return std::string(bytes.begin(), bytes.end());
}

void put_vec3(ByteWriter& w, const Vec3& v) {
  for (int c = 0; c < 3; ++c) w.put<double>(v[c]);
}
Vec3 get_vec3(ByteReader& r, const char* what) {
  Vec3 v;
  for (int c = 0; c < 3; ++c) v[c] = r.get<double>(what);
  return v;
}
void put_ints(ByteWriter& w, const std::vector<int>& v) {
  w.put<uint32_t>(static_cast<uint32_t>(v.size()));
  for (int x : v) w.put<int32_t>(x);
}
std::vector<int> get_ints(ByteReader& r, const char* what) {
  std::vector<int> v(r.get_count(4, what));
  for (int& x : v) x = r.get<int32_t>(what);
  return v;
}

void encode(const MarkerPcaModel& p, ByteWriter& w) {
  w.put<uint32_t>(static_cast<uint32_t>(p.mean.size()));
  w.put<uint32_t>(static_cast<uint32_t>(p.variance.size()));
  w.put<int32_t>(p.training_frames);
  w.put<double>(p.residual_variance);
  for (Eigen::Index k = 0; k < p.mean.size(); ++k) w.put<double>(p.mean(k));
  for (Eigen::Index k = 0; k < p.variance.size(); ++k) w.put<double>(p.variance(k));
  for (Eigen::Index k = 0; k < p.basis.size(); ++k) w.put<double>(p.basis.data()[k]);
  for (Eigen::Index k = 0; k < p.slot_calibration.size(); ++k) w.put<double>(p.slot_calibration(k));
  w.put<double>(p.rigid_variance);
}

MarkerPcaModel decode_pca(ByteReader& r, const std::string& what) {
  MarkerPcaModel p;
  const uint32_t dims = r.get<uint32_t>("PCA dimensions"), components = r.get<uint32_t>("PCA components");
  if (dims > 3 * SubjectModel::kMaxRing || dims % 3 != 0 || components > dims)
    throw SubjectPayloadError(what + " has implausible shape");
  p.training_frames = r.get<int32_t>("PCA training frames");
  p.residual_variance = r.get<double>("PCA residual variance");
  p.mean.resize(dims);
  p.variance.resize(components);
  p.basis.resize(dims, components);
  for (uint32_t k = 0; k < dims; ++k) p.mean(k) = r.get<double>("PCA mean");
  for (uint32_t k = 0; k < components; ++k) p.variance(k) = r.get<double>("PCA variance");
  for (Eigen::Index k = 0; k < p.basis.size(); ++k) p.basis.data()[k] = r.get<double>("PCA basis");
  p.slot_calibration.resize(dims / 3);
  for (uint32_t k = 0; k < dims / 3; ++k) p.slot_calibration(k) = r.get<double>("PCA slot calibration");
  p.rigid_variance = r.get<double>("PCA rigid variance");
  return p;
}

// Version 5: the regions and their PCA models, after the deformation model (a count of 0: none).
void encode_regions(const SubjectModel& m, ByteWriter& w) {
  w.put<uint32_t>(static_cast<uint32_t>(m.region_pca.size()));
  if (m.region_pca.empty()) return;
  put_ints(w, m.region_offsets);
  put_ints(w, m.region);
  for (const MarkerPcaModel& p : m.region_pca) encode(p, w);
}

void decode_regions(ByteReader& r, SubjectModel& m) {
  const uint32_t count = r.get<uint32_t>("region count");
  if (count == 0) return;
  if (count != static_cast<uint32_t>(m.marker_count()))
    throw SubjectPayloadError("region models for " + std::to_string(count) + " markers");
  m.region_offsets = get_ints(r, "region offsets");
  m.region = get_ints(r, "regions");
  for (uint32_t i = 0; i < count; ++i) m.region_pca.push_back(decode_pca(r, "region PCA model of marker " + std::to_string(i)));
}

void encode(const SubjectModel& m, ByteWriter& w) {
  w.put<uint32_t>(static_cast<uint32_t>(m.marker_count()));
  for (int i = 0; i < m.marker_count(); ++i) {
    w.put_string(m.marker_names[i]);
    put_vec3(w, m.reference_positions[i]);
  }
  w.put<uint32_t>(static_cast<uint32_t>(m.triangles.size()));
  for (const auto& t : m.triangles)
    for (int v : t) w.put<int32_t>(v);
  put_ints(w, m.ring_offsets);
  put_ints(w, m.ring);
  for (const Vec3& p : m.ring_local_reference) put_vec3(w, p);
  for (const Eigen::Matrix3d& r : m.local_reference_frames)
    for (int k = 0; k < 9; ++k) w.put<double>(r.data()[k]);
  put_ints(w, m.anchor_offsets);
  put_ints(w, m.anchors);
  for (const MarkerPcaModel& p : m.pca) encode(p, w);
  w.put<double>(m.parameters.alpha1);
  w.put<double>(m.parameters.alpha2);
}

void encode(const DeformationModel* d, ByteWriter& w) {
  w.put<uint8_t>(d ? 1 : 0);
  if (!d) return;
  w.put<uint32_t>(static_cast<uint32_t>(d->vertex_count()));
  for (const Vec3& v : d->reference_vertices) put_vec3(w, v);
  w.put<uint32_t>(static_cast<uint32_t>(d->faces.size()));
  for (const auto& f : d->faces)
    for (int v : f) w.put<int32_t>(v);
  w.put<uint32_t>(static_cast<uint32_t>(d->part_count()));
  for (const std::string& name : d->part_names) w.put_string(name);
  put_ints(w, d->part_member_offsets);
  w.put<uint32_t>(static_cast<uint32_t>(d->part_members.size()));
  for (const PartMember& m : d->part_members) {
    w.put<int32_t>(m.marker);
    w.put<double>(m.weight);
  }
  put_ints(w, d->vertex_influence_offsets);
  w.put<uint32_t>(static_cast<uint32_t>(d->vertex_influences.size()));
  for (const PartInfluence& inf : d->vertex_influences) {
    w.put<int32_t>(inf.part);
    w.put<double>(inf.weight);
  }
  w.put<double>(d->registration_rms_mm);
  w.put<uint32_t>(static_cast<uint32_t>(d->part_rbf_ridge.size()));  // version 3
  for (double ridge : d->part_rbf_ridge) w.put<double>(ridge);
  w.put<uint32_t>(static_cast<uint32_t>(d->part_quadratic_ridge.size()));  // version 4
  for (double ridge : d->part_quadratic_ridge) w.put<double>(ridge);
}

std::optional<DeformationModel> decode_deformation(ByteReader& r, uint32_t version) {
  if (r.get<uint8_t>("deformation model flag") == 0) return std::nullopt;
  DeformationModel d;
  d.reference_vertices.resize(r.get_count(24, "mesh vertices"));
  for (Vec3& v : d.reference_vertices) v = get_vec3(r, "mesh vertices");
  d.faces.resize(r.get_count(12, "mesh faces"));
  for (auto& f : d.faces)
    for (int& v : f) v = r.get<int32_t>("mesh faces");
  const uint32_t parts = r.get_count(4, "part names");
  for (uint32_t p = 0; p < parts; ++p) d.part_names.push_back(get_string(r, 256, "part names"));
  d.part_member_offsets = get_ints(r, "part member offsets");
  d.part_members.resize(r.get_count(12, "part members"));
  for (PartMember& m : d.part_members) {
    m.marker = r.get<int32_t>("part members");
    m.weight = r.get<double>("part members");
  }
  d.vertex_influence_offsets = get_ints(r, "vertex influence offsets");
  d.vertex_influences.resize(r.get_count(12, "vertex influences"));
  for (PartInfluence& inf : d.vertex_influences) {
    inf.part = r.get<int32_t>("vertex influences");
    inf.weight = r.get<double>("vertex influences");
  }
  d.registration_rms_mm = r.get<double>("registration error");
  if (version >= 3) {
    d.part_rbf_ridge.resize(r.get_count(8, "part RBF ridges"));
    for (double& ridge : d.part_rbf_ridge) ridge = r.get<double>("part RBF ridges");
  }
  if (version >= 4) {
    d.part_quadratic_ridge.resize(r.get_count(8, "part quadratic ridges"));
    for (double& ridge : d.part_quadratic_ridge) ridge = r.get<double>("part quadratic ridges");
  }
  return d;
}

// Version 6: the fitted body's skeleton, per-part quadratic flags and rest vertices.
void encode_fitted_body(const DeformationModel* d, ByteWriter& w) {
  const bool fitted = d && (!d->skeleton.empty() || !d->part_quadratic.empty() || !d->rest_vertices.empty());
  w.put<uint8_t>(fitted ? 1 : 0);
  if (!fitted) return;
  const SegmentSkeleton& s = d->skeleton;
  w.put<uint32_t>(static_cast<uint32_t>(s.segments.size()));
  for (const SkeletonSegment& segment : s.segments) {
    w.put_string(segment.name);
    w.put<int32_t>(segment.parent);
    put_vec3(w, segment.pivot);
  }
  put_ints(w, s.marker_weight_offsets);
  w.put<uint32_t>(static_cast<uint32_t>(s.marker_weights.size()));
  for (const SegmentWeight& weight : s.marker_weights) {
    w.put<int32_t>(weight.segment);
    w.put<double>(weight.weight);
  }
  put_ints(w, s.part_segment);
  w.put<uint32_t>(static_cast<uint32_t>(d->part_quadratic.size()));
  for (uint8_t q : d->part_quadratic) w.put<uint8_t>(q);
  w.put<uint32_t>(static_cast<uint32_t>(d->rest_vertices.size()));
  for (const Vec3& v : d->rest_vertices) put_vec3(w, v);
}

void decode_fitted_body(ByteReader& r, std::optional<DeformationModel>& d) {
  if (r.get<uint8_t>("fitted body flag") == 0) return;
  if (!d) throw SubjectPayloadError("a fitted body without a deformation model");
  SegmentSkeleton& s = d->skeleton;
  s.segments.resize(r.get_count(4 + 4 + 24, "skeleton segments"));
  for (SkeletonSegment& segment : s.segments) {
    segment.name = get_string(r, 256, "skeleton segment name");
    segment.parent = r.get<int32_t>("skeleton segment parent");
    segment.pivot = get_vec3(r, "skeleton segment joint");
  }
  s.marker_weight_offsets = get_ints(r, "marker weight offsets");
  s.marker_weights.resize(r.get_count(12, "marker weights"));
  for (SegmentWeight& weight : s.marker_weights) {
    weight.segment = r.get<int32_t>("marker weights");
    weight.weight = r.get<double>("marker weights");
  }
  s.part_segment = get_ints(r, "part segments");
  if (s.segments.empty()) s.marker_weight_offsets = {0};  // no skeleton: written as empty
  d->part_quadratic.resize(r.get_count(1, "part quadratic flags"));
  for (uint8_t& q : d->part_quadratic) q = r.get<uint8_t>("part quadratic flags");
  d->rest_vertices.resize(r.get_count(24, "rest vertices"));
  for (Vec3& v : d->rest_vertices) v = get_vec3(r, "rest vertices");
}

SubjectModel decode(ByteReader& r) {
  SubjectModel m;
  const uint32_t n = r.get_count(4 + 24, "markers");
  for (uint32_t i = 0; i < n; ++i) {
    m.marker_names.push_back(get_string(r, 4096, "marker name"));
    m.reference_positions.push_back(get_vec3(r, "marker reference position"));
  }
  m.triangles.resize(r.get_count(12, "triangles"));
  for (auto& t : m.triangles)
    for (int& v : t) v = r.get<int32_t>("triangles");
  m.ring_offsets = get_ints(r, "one-ring offsets");
  m.ring = get_ints(r, "one-rings");
  if (r.ok() && m.ring.size() > r.remaining() / 24)
    throw SubjectPayloadError("one-ring larger than the file");
  for (size_t k = 0; k < m.ring.size(); ++k)
    m.ring_local_reference.push_back(get_vec3(r, "one-ring local positions"));
  for (uint32_t i = 0; i < n; ++i) {
    Eigen::Matrix3d f;
    for (int k = 0; k < 9; ++k) f.data()[k] = r.get<double>("local reference frames");
    m.local_reference_frames.push_back(f);
  }
  m.anchor_offsets = get_ints(r, "anchor offsets");
  m.anchors = get_ints(r, "anchors");
  for (uint32_t i = 0; i < n; ++i) m.pca.push_back(decode_pca(r, "PCA model of marker " + std::to_string(i)));
  m.parameters.alpha1 = r.get<double>("alpha1");
  m.parameters.alpha2 = r.get<double>("alpha2");
  return m;
}

// ---- Every value read is checked: the model's own validate() checks its shape, not its numbers,
// and a NaN or 1e300 in a reference position, a local frame, an alpha or the PCA once went into
// the filler (non-finite markers were then published).

// Reference positions and vertices lie within this of the origin (mm): 1 km.
constexpr double kMaxCoordinateMm = 1e6;

bool finite_within(double value, double bound) { return std::isfinite(value) && std::abs(value) <= bound; }

bool position_ok(const Vec3& p) {
  return finite_within(p.x(), kMaxCoordinateMm) && finite_within(p.y(), kMaxCoordinateMm) && finite_within(p.z(), kMaxCoordinateMm);
}

// A name fit for logs and for the subscribers: not empty, at most 256 bytes, printable ASCII or
// UTF-8 (no control characters).
bool name_ok(const std::string& name) {
  if (name.empty() || name.size() > 256) return false;
  for (const char c : name) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7F) return false;
  }
  return true;
}

std::string pca_problem(const MarkerPcaModel& p) {
  for (Eigen::Index k = 0; k < p.mean.size(); ++k)
    if (!finite_within(p.mean(k), kMaxCoordinateMm)) return "a mean that is not a finite coordinate";
  for (Eigen::Index k = 0; k < p.variance.size(); ++k)
    if (!std::isfinite(p.variance(k)) || p.variance(k) < 0) return "a variance that is negative or not finite";
  for (Eigen::Index k = 0; k < p.basis.size(); ++k)
    if (!finite_within(p.basis.data()[k], 1.0 + 1e-6)) return "a basis value outside [-1, 1]";
  for (Eigen::Index k = 0; k < p.slot_calibration.size(); ++k)
    if (!std::isfinite(p.slot_calibration(k)) || p.slot_calibration(k) < 0) return "a calibration that is negative or not finite";
  if (!std::isfinite(p.residual_variance) || p.residual_variance < 0) return "a residual variance that is negative or not finite";
  if (!std::isfinite(p.rigid_variance) || p.rigid_variance < 0) return "a rigid variance that is negative or not finite";
  if (p.training_frames < 0) return "a negative count of training frames";
  return "";
}

std::string values_problem(const SubjectFile& file) {
  const SubjectModel& m = file.model;
  std::unordered_set<std::string> names;
  for (size_t i = 0; i < m.marker_names.size(); ++i) {
    const std::string which = "marker " + std::to_string(i);
    if (!name_ok(m.marker_names[i])) return which + "'s name is empty, longer than 256 bytes or holds a control character";
    if (!names.insert(m.marker_names[i]).second) return which + "'s name " + quoted_text(m.marker_names[i]) + " is another marker's too";
    if (!position_ok(m.reference_positions[i])) return which + "'s reference position is not finite or beyond 1 km";
    const Eigen::Matrix3d& frame = m.local_reference_frames[i];
    if (!frame.allFinite() || (frame * frame.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3)
      return which + "'s local reference frame is not a rotation";
    if (const std::string bad = pca_problem(m.pca[i]); !bad.empty()) return which + "'s PCA model has " + bad;
  }
  for (const Vec3& p : m.ring_local_reference)
    if (!position_ok(p)) return "a one-ring member's local position is not finite or beyond 1 km";
  for (size_t i = 0; i < m.region_pca.size(); ++i)
    if (const std::string bad = pca_problem(m.region_pca[i]); !bad.empty())
      return "marker " + std::to_string(i) + "'s region PCA model has " + bad;
  const FillParameters& fill = m.parameters;
  if (!(fill.alpha1 > 0 && fill.alpha1 <= 10) || !(fill.alpha2 > 0 && fill.alpha2 <= 10))
    return "the fill parameters alpha1 and alpha2 must be in (0, 10]";
  if (!file.deformation) return "";
  const DeformationModel& d = *file.deformation;
  for (const Vec3& v : d.reference_vertices)
    if (!position_ok(v)) return "a mesh vertex is not finite or beyond 1 km";
  for (const Vec3& v : d.rest_vertices)
    if (!position_ok(v)) return "a rest-pose vertex is not finite or beyond 1 km";
  for (const SkeletonSegment& segment : d.skeleton.segments) {
    if (!name_ok(segment.name)) return "a skeleton segment's name is empty, longer than 256 bytes or holds a control character";
    if (!position_ok(segment.pivot)) return "skeleton segment " + quoted_text(segment.name) + "'s joint is not finite or beyond 1 km";
  }
  std::unordered_set<std::string> parts;
  for (const std::string& name : d.part_names) {
    if (!name_ok(name)) return "a part's name is empty, longer than 256 bytes or holds a control character";
    if (!parts.insert(name).second) return "part name " + quoted_text(name) + " is given twice";
  }
  for (const PartMember& member : d.part_members)
    if (!finite_within(member.weight, 1e6)) return "a part's marker weight is not finite";
  for (const PartInfluence& influence : d.vertex_influences)
    if (!std::isfinite(influence.weight) || influence.weight < 0 || influence.weight > 1 + 1e-6) return "a vertex weight outside [0, 1]";
  for (const std::vector<double>* ridges : {&d.part_rbf_ridge, &d.part_quadratic_ridge})
    for (double ridge : *ridges)
      if (!std::isfinite(ridge) || ridge < 0) return "a part's ridge is negative or not finite";
  if (!std::isfinite(d.registration_rms_mm) || d.registration_rms_mm < 0) return "the registration error is negative or not finite";
  return "";
}

}  // namespace

void write_subject(const SubjectModel& model, const std::string& path) { write_subject(model, nullptr, path); }

void write_subject(const SubjectModel& model, const DeformationModel* deformation, const std::string& path) {
  const std::string problem = model.validate();
  if (!problem.empty()) throw FileError(path, "refusing to write an inconsistent subject model: " + problem);
  if (deformation) {
    const std::string bad = deformation->validate(model.marker_count());
    if (!bad.empty()) throw FileError(path, "refusing to write an inconsistent " + bad);
  }
  ByteWriter payload_writer;
  encode(model, payload_writer);
  encode(deformation, payload_writer);
  encode_regions(model, payload_writer);
  encode_fitted_body(deformation, payload_writer);
  const std::vector<unsigned char>& payload = payload_writer.bytes();
  ByteWriter w;
  w.put_bytes(kMagic, sizeof kMagic);
  w.put<uint32_t>(kSubjectFileVersion);
  w.put<uint64_t>(payload.size());
  w.put_bytes(payload.data(), payload.size());
  w.put<uint32_t>(crc32(payload.data(), payload.size()));
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw FileError(path, "cannot open for writing");
  out.write(reinterpret_cast<const char*>(w.bytes().data()), static_cast<std::streamsize>(w.bytes().size()));
  if (!out) throw FileError(path, "write failed");
}

SubjectFile read_subject_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError(path, "cannot open subject file");
  const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return read_subject_bytes(bytes, path);
}

SubjectFile read_subject_bytes(std::span<const unsigned char> bytes, const std::string& path) {
  if (bytes.size() < 24 || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw FileError(path, "not a skinstream subject file (bad magic)");
  ByteReader header(bytes.subspan(8, 12));
  const uint32_t version = header.get<uint32_t>("version");
  if (version < 1 || version > kSubjectFileVersion)
    throw FileError(path, "subject file version " + std::to_string(version) + ", this build reads versions 1 to " +
                              std::to_string(kSubjectFileVersion) + "; rebuild it with skinstream build-subject");
  const uint64_t size = header.get<uint64_t>("payload size");
  if (size != bytes.size() - 24)
    throw FileError(path, "truncated or padded: header says " + std::to_string(size) + " payload bytes, file holds " +
                              std::to_string(bytes.size() - 24));
  const unsigned char* payload = bytes.data() + 20;
  uint32_t stored_crc;
  std::memcpy(&stored_crc, bytes.data() + bytes.size() - 4, 4);
  if (crc32(payload, size) != stored_crc) throw FileError(path, "corrupt: CRC-32 mismatch");
  SubjectFile file;
  ByteReader r(payload, size);
  try {
    file.model = decode(r);
    if (version >= 2) file.deformation = decode_deformation(r, version);
    if (version >= 5) decode_regions(r, file.model);
    if (version >= 6) decode_fitted_body(r, file.deformation);
  } catch (const SubjectPayloadError& e) {
    throw FileError(path, std::string("corrupt subject payload: ") + e.what());
  }
  if (!r.ok()) throw FileError(path, "corrupt subject payload: " + r.error().message());
  if (r.remaining() != 0)
    throw FileError(path, "corrupt subject payload: " + std::to_string(r.remaining()) +
                              " unexpected bytes after the model");
  const std::string problem = file.model.validate();
  if (!problem.empty()) throw FileError(path, "inconsistent subject model: " + problem);
  if (file.deformation) {
    const std::string bad = file.deformation->validate(file.model.marker_count());
    if (!bad.empty()) throw FileError(path, "inconsistent " + bad);
  }
  if (const std::string bad = values_problem(file); !bad.empty()) throw FileError(path, "bad value: " + bad);
  return file;
}

SubjectModel read_subject(const std::string& path) { return std::move(read_subject_file(path).model); }

}  // namespace skinstream
