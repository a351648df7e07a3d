// skinstream convert IN OUT: C3D <-> TRC by extension.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "clients/skinstream/commands.h"
#include "protocol/capture_file.h"

namespace skinstream::cli {

void add_convert(CLI::App& app) {
  auto* cmd = app.add_subcommand("convert", "Convert a capture between C3D and TRC (format from the extensions)");
  static std::string in, out;
  cmd->add_option("IN", in, "input capture")->required();
  cmd->add_option("OUT", out, "output capture")->required();
  cmd->callback([] {
    const Capture capture = read_capture(in);
    write_capture(capture, out);
    std::printf("wrote %s: %d channels, %d frames\n", out.c_str(), capture.point_count(), capture.frame_count);
  });
}

}  // namespace skinstream::cli
