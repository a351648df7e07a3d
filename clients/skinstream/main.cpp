// skinstream: offline tools around the skin capture pipeline (inspect, convert, build a
// subject model, fill gaps, evaluate). Errors print one line to stderr and exit non-zero.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "clients/skinstream/commands.h"

namespace skinstream::cli {
int exit_code = 0;
}

int main(int argc, char** argv) {
  CLI::App app{"skinstream: dense marker capture to deforming skin (Park & Hodgins 2006)"};
  app.require_subcommand(1);
  skinstream::cli::add_info(app);
  skinstream::cli::add_convert(app);
  skinstream::cli::add_build_subject(app);
  skinstream::cli::add_fill(app);
  skinstream::cli::add_eval_fill(app);
  skinstream::cli::add_synth(app);
  skinstream::cli::add_eval_deform(app);
  skinstream::cli::add_deform(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "skinstream: error: %s\n", e.what());
    return 1;
  }
  return skinstream::cli::exit_code;
}
