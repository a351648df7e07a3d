#pragma once
// Every configuration key once: where it lives in DaemonConfig, its flag, its allowed values and
// its documentation. Reading a file (apply_json), printing (to_json), the command line, the range
// checks (validate) and config/skinstreamd.reference.json all come from this table, so a key is
// added or changed in one place. A key's default is its DaemonConfig member's initializer.

#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "server/config.h"

namespace CLI {
class App;
class Option;
}  // namespace CLI

namespace skinstream::server {

struct ConfigKey {
  std::string name{};       // the JSON key
  std::string flag{};       // its command-line flag ("--http-port"); empty: the file only
  bool new_group = false;   // a blank line before it in the reference file
  bool source = false;      // one of the exclusive sources: a source flag replaces the file's source
  std::string flag_help{};  // the flag's --help text
  // "" or what is wrong with the key's value, naming the key (validate() prefixes "configuration: ").
  std::function<std::string(const DaemonConfig&)> problem{};
  std::string doc{};  // the reference file's comment above the key, lines apart by '\n'
  // Sets the key from a JSON object that has it; throws ConfigError naming `origin`.
  std::function<void(const nlohmann::json& object, DaemonConfig&, const std::string& origin)> read{};
  // The key's value as printed; none: read only (the one-subject form "subject").
  std::function<nlohmann::json(const DaemonConfig&)> write{};
  // Declares the flag, its value kept in `flags` ...
  std::function<CLI::Option*(CLI::App&, DaemonConfig& flags)> add_flag{};
  // ... and copies that value onto the configuration when the flag is given.
  std::function<void(const DaemonConfig& flags, DaemonConfig&)> take_flag{};
};

// In the reference file's order.
const std::vector<ConfigKey>& config_keys();

// The text of config/skinstreamd.reference.json: every printed key with its comment and default.
std::string reference_config();

}  // namespace skinstream::server
