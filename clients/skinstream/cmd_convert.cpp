#include "clients/skinstream/cmd_convert.h"

#include "protocol/files/capture_file.h"

namespace skinstream::cli {

int run_convert(const ConvertOptions& o, std::FILE* out) {
  const Capture capture = read_capture(o.in_path);
  write_capture(capture, o.out_path);
  std::fprintf(out, "wrote %s: %d channels, %d frames\n", o.out_path.c_str(), capture.point_count(), capture.frame_count);
  return 0;
}

}  // namespace skinstream::cli
