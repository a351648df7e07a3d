// Writes TRC marker files in millimetres. Numbers use the shortest text that reads back to the
// same double, so a TRC round trip is exact.
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "protocol/files/capture_checks.h"
#include "protocol/files/file_error.h"
#include "protocol/files/trc.h"

namespace skinstream {
namespace {

void append_number(std::string& out, double value) {
  char text[32];
  const auto result = std::to_chars(text, text + sizeof text, value);
  out.append(text, result.ptr);
}

void check_trc_writable(const Capture& capture, const std::string& path) {
  check_capture_shape(capture, path);
  for (const std::string& label : capture.labels)
    if (label.find_first_of("\t\r\n") != std::string::npos)
      throw FileError(path, "label '" + label + "' holds a tab or line break, which TRC cannot store");
}

std::string header(const Capture& capture, const std::string& path) {
  std::string out = "PathFileType\t4\t(X/Y/Z)\t" + std::filesystem::path(path).filename().string() + "\n";
  out +=
      "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames\n";
  for (int i = 0; i < 2; ++i) {
    append_number(out, capture.rate_hz);
    out += '\t';
  }
  out += std::to_string(capture.frame_count) + "\t" + std::to_string(capture.point_count()) + "\tmm\t";
  append_number(out, capture.rate_hz);
  out += "\t" + std::to_string(capture.first_frame) + "\t" + std::to_string(capture.frame_count) + "\n";

  out += "Frame#\tTime";  // each name above its X column, two empty cells for Y and Z
  for (const std::string& label : capture.labels) out += "\t" + label + "\t\t";
  out += "\n\t";
  for (int m = 1; m <= capture.point_count(); ++m) {
    const std::string n = std::to_string(m);
    out += "\tX" + n + "\tY" + n + "\tZ" + n;
  }
  out += "\n\n";
  return out;
}

}  // namespace

void write_trc(const Capture& capture, const std::string& path) {
  check_trc_writable(capture, path);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw FileError(path, "cannot open for writing");
  out << header(capture, path);

  std::string rows;
  for (int f = 0; f < capture.frame_count; ++f) {
    rows += std::to_string(capture.first_frame + f);
    rows += '\t';
    append_number(rows, f / capture.rate_hz);
    for (int p = 0; p < capture.point_count(); ++p) {
      const Vec3& position = capture.at(f, p);
      const bool present = is_present(position);
      for (int axis = 0; axis < 3; ++axis) {
        rows += '\t';
        if (present) append_number(rows, position[axis]);  // a missing marker: empty cells
      }
    }
    rows += '\n';
    if (rows.size() > (1u << 20)) {
      out << rows;
      rows.clear();
    }
  }
  out << rows;
  out.close();
  if (!out) throw FileError(path, "write failed");
}

}  // namespace skinstream
