#pragma once
// skinstream's command line: one subcommand, parsed into its options struct, so that a command
// can be run (and tested) without CLI11. cmd_<name>.{h,cpp} holds each command.
#include <optional>
#include <string>

#include "clients/skinstream/cmd_build_subject.h"
#include "clients/skinstream/cmd_convert.h"
#include "clients/skinstream/cmd_deform.h"
#include "clients/skinstream/cmd_eval_actor.h"
#include "clients/skinstream/cmd_eval_deform.h"
#include "clients/skinstream/cmd_eval_fill.h"
#include "clients/skinstream/cmd_fill.h"
#include "clients/skinstream/cmd_info.h"
#include "clients/skinstream/cmd_synth.h"

namespace skinstream::cli {

// Every command's options with their defaults; parsing fills in the one named by `command`.
struct CommandLine {
  std::string command;  // the subcommand given: "info", "fill", "eval-fill", ...
  InfoOptions info;
  ConvertOptions convert;
  BuildSubjectOptions build_subject;
  FillOptions fill;
  EvalFillOptions eval_fill;
  SynthOptions synth;
  EvalDeformOptions eval_deform;
  DeformOptions deform;
  EvalActorOptions eval_actor;
};

// Parses argv into `out`. Returns the exit code to leave with instead (after --help, or a usage
// error already printed to stderr), or nothing when the command should run. Throws
// std::invalid_argument for a value only the command can judge (synth --mesh-out-every N).
std::optional<int> parse_command_line(int argc, const char* const* argv, CommandLine& out);

}  // namespace skinstream::cli
