#pragma once
// The subcommands of the offline `skinstream` tool, one file each (cmd_<name>.cpp).
// Each adds itself to the app; the callback runs the command and sets the exit code.
namespace CLI {
class App;
}

namespace skinstream::cli {

// Set by a command's callback; main returns it.
extern int exit_code;

void add_info(CLI::App& app);
void add_convert(CLI::App& app);
void add_build_subject(CLI::App& app);
void add_fill(CLI::App& app);
void add_eval_fill(CLI::App& app);
void add_synth(CLI::App& app);
void add_eval_deform(CLI::App& app);
void add_deform(CLI::App& app);

}  // namespace skinstream::cli
