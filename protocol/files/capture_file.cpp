#include "protocol/files/capture_file.h"

#include <cctype>
#include <filesystem>

#include "protocol/files/c3d.h"
#include "protocol/files/file_error.h"
#include "protocol/files/trc.h"

namespace skinstream {
namespace {

enum class CaptureFormat { C3d, Trc };

CaptureFormat format_of(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension == ".c3d") return CaptureFormat::C3d;
  if (extension == ".trc") return CaptureFormat::Trc;
  throw FileError(path, extension.empty()
                            ? "no file extension (expected .c3d or .trc)"
                            : "unknown capture file extension '" + extension + "' (expected .c3d or .trc)");
}

}  // namespace

Capture read_capture(const std::string& path) {
  return format_of(path) == CaptureFormat::C3d ? read_c3d(path) : read_trc(path);
}

void write_capture(const Capture& capture, const std::string& path) {
  if (format_of(path) == CaptureFormat::C3d)
    write_c3d(capture, path);
  else
    write_trc(capture, path);
}

}  // namespace skinstream
