#pragma once
// TRC marker files (Motion Analysis; the marker format OpenSim reads): tab-separated text with
// a PathFileType line, a header key/value pair of lines (DataRate, NumFrames, NumMarkers,
// Units...), a marker name row, an X1 Y1 Z1 row, then one row per frame: Frame#, Time and
// x y z per marker, empty cells for a missing marker. Positions come back in millimetres.
#include <string>
#include <string_view>

#include "core/capture.h"

namespace skinstream {

Capture read_trc(const std::string& path);                        // throws FileError
// The same from a whole file's text in memory; `name` stands for the path in errors.
Capture read_trc_bytes(std::string_view text, const std::string& name);
void write_trc(const Capture& capture, const std::string& path);  // throws FileError

}  // namespace skinstream
