#pragma once
// The subject file: a SubjectModel on disk.
//
//   bytes 0-7   magic "SKSUBJ\r\n" (the CR LF catches text-mode mangling)
//   bytes 8-11  u32 format version (kSubjectFileVersion)
//   bytes 12-19 u64 payload size
//   payload     little-endian: markers, reference pose, triangles, one-rings, local frames,
//               anchors, PCA models, fill parameters (see subject_file.cpp, in that order);
//               version 2 adds a flag byte and, when set, the deformation model of section 5
//               (registered mesh, parts with marker weights, vertex weights); version 3
//               appends to it each part's ridge of eq. 7 (a count, then doubles), version 4
//               each part's quadratic ridge; version 5 appends, after the deformation model, the
//               regions and their PCA models (a count of markers, 0 for none; then the region
//               offsets and members, and one PCA model per marker as the one-ring models are);
//               version 6 appends the fitted body of a sparse marker set: a flag byte, then the
//               skeleton (segments: name, parent, pivot; each marker's segment weights; each
//               part's segment), each part's quadratic flag and the rest vertices (counts first,
//               0 for none)
//   last 4      u32 CRC-32 of the payload
//
// Another version, a bad magic, a size or CRC mismatch or an inconsistent model is rejected
// with a FileError that says which.

#include <optional>
#include <span>
#include <string>

#include "core/deform/deformation_model.h"
#include "core/subject_model.h"

namespace skinstream {

// Reads 1 (no deformation model), 2 (no ridges), 3 (no quadratic ridges), 4 (no regions), 5 (no
// fitted body) and 6.
inline constexpr uint32_t kSubjectFileVersion = 6;

struct SubjectFile {
  SubjectModel model;
  std::optional<DeformationModel> deformation;  // absent: built without --mesh
};

void write_subject(const SubjectModel& model, const std::string& path);
void write_subject(const SubjectModel& model, const DeformationModel* deformation, const std::string& path);
SubjectFile read_subject_file(const std::string& path);
// The same from a whole file's bytes in memory; `name` stands for the path in errors.
SubjectFile read_subject_bytes(std::span<const unsigned char> bytes, const std::string& name);
SubjectModel read_subject(const std::string& path);  // the marker model only

}  // namespace skinstream
