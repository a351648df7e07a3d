// skinstream: offline tools around the skin capture pipeline (inspect, convert, build a
// subject model, fill gaps, evaluate). Arguments, then the command. Errors print one line to
// stderr and exit non-zero.
#include <cstdio>
#include <exception>
#include <stdexcept>

#include "clients/skinstream/command_line.h"

namespace {

int run_command(const skinstream::cli::CommandLine& c, std::FILE* out) {
  using namespace skinstream::cli;
  if (c.command == "info") return run_info(c.info, out);
  if (c.command == "convert") return run_convert(c.convert, out);
  if (c.command == "build-subject") return run_build_subject(c.build_subject, out);
  if (c.command == "fill") return run_fill(c.fill, out);
  if (c.command == "eval-fill") return run_eval_fill(c.eval_fill, out);
  if (c.command == "synth") return run_synth(c.synth, out);
  if (c.command == "eval-deform") return run_eval_deform(c.eval_deform, out);
  if (c.command == "deform") return run_deform(c.deform, out);
  if (c.command == "eval-actor") return run_eval_actor(c.eval_actor, out);
  throw std::logic_error("no command " + c.command);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    skinstream::cli::CommandLine command_line;
    if (const auto exit_code = skinstream::cli::parse_command_line(argc, argv, command_line)) return *exit_code;
    return run_command(command_line, stdout);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "skinstream: error: %s\n", e.what());
    return 1;
  }
}
