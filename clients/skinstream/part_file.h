#pragma once
// The JSON files that name markers: {"marker name": number, ...}. build-subject reads landmarks
// (mesh vertex per marker) and parts (part per marker) from them, and writes the parts it used
// in the same form, so a segmentation can be adjusted by hand (as the paper did) and read back
// by build-subject or eval-deform.
#include <string>
#include <vector>

#include "core/subject_model.h"

namespace skinstream::cli {

// One non-negative number per subject marker, -1 when not listed. Throws FileError for a file
// that cannot be read, is not a JSON object, names an unknown marker or holds anything but a
// non-negative integer; `what` names the number in the messages ("part index").
std::vector<int> read_marker_map(const std::string& path, const SubjectModel& model, const char* what);

// A part per marker. A marker in no triangle of the marker surface decides no part and may be
// left out (it gets part 0); any other missing marker is a FileError.
std::vector<int> read_part_file(const std::string& path, const SubjectModel& model);

// {"marker name": part} in the subject's marker order; markers with a negative part (in no
// triangle) left out. Throws FileError when the file cannot be written.
void write_part_file(const std::string& path, const SubjectModel& model, const std::vector<int>& marker_part);

// The one-line warning on stderr when parts of a part file hold no triangle (dropped by the
// builder, the others renumbered); nothing when `unused` is empty.
void warn_unused_parts(const std::string& path, const std::vector<int>& unused);

}  // namespace skinstream::cli
