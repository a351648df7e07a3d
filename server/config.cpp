#include "server/config.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "server/config_keys.h"
#include "server/ingest/source_spec.h"

namespace skinstream::server {

SubjectConfig parse_subject(const std::string& text) {
  const size_t equals = text.find('=');
  if (equals == std::string::npos || equals == 0 || text.find('/') < equals) return {"", text};
  return {text.substr(0, equals), text.substr(equals + 1)};
}

void apply_json(const nlohmann::json& json, DaemonConfig& c, const std::string& origin) {
  if (!json.is_object()) throw ConfigError(origin + ": the configuration must be a JSON object");
  const std::vector<ConfigKey>& keys = config_keys();
  for (const auto& [name, value] : json.items())
    if (std::none_of(keys.begin(), keys.end(), [&](const ConfigKey& key) { return key.name == name; }))
      throw ConfigError(origin + ": unknown key \"" + name + "\"");
  for (const ConfigKey& key : keys)
    if (json.contains(key.name)) key.read(json, c, origin);
}

DaemonConfig load_config_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open the configuration file");
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(text.str(), nullptr, true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::parse_error& e) {
    throw ConfigError(path + ": not valid JSON (byte " + std::to_string(e.byte) + ")");
  }
  DaemonConfig config;
  apply_json(json, config, path);
  return config;
}

nlohmann::json to_json(const DaemonConfig& c) {
  nlohmann::json json = nlohmann::json::object();
  for (const ConfigKey& key : config_keys())
    if (key.write) json[key.name] = key.write(c);
  return json;
}

nlohmann::json printable(const DaemonConfig& c) {
  nlohmann::json json = to_json(c);
  if (!c.subscriber_token.empty())
    json["subscriber_token"] = "(set, " + std::to_string(c.subscriber_token.size()) + " bytes, not shown)";
  return json;
}

void validate(const DaemonConfig& c) {
  auto fail = [](const std::string& what) { throw ConfigError("configuration: " + what); };
  source_spec_of(c);  // ConfigError when more than one source is given
  for (const ConfigKey& key : config_keys())
    if (key.problem)
      if (const std::string problem = key.problem(c); !problem.empty()) fail(problem);
}

std::optional<HostPort> parse_host_port(const std::string& text) {
  const size_t colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0) return std::nullopt;
  const std::string port = text.substr(colon + 1);
  if (port.empty() || port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos)
    return std::nullopt;
  const int number = std::stoi(port);
  if (number < 1 || number > 65535) return std::nullopt;
  return HostPort{text.substr(0, colon), static_cast<uint16_t>(number)};
}

std::optional<HostPort> parse_host_with_port(const std::string& text, uint16_t default_port) {
  if (text.empty()) return std::nullopt;
  if (text.find(':') == std::string::npos) return HostPort{text, default_port};
  return parse_host_port(text);
}

std::optional<CommandLine> parse_command_line(int argc, const char* const* argv, int& out_exit_code) {
  CLI::App app{
      "skinstreamd: live marker frames in, gap-filled deforming skin meshes out to every subscriber"};
  std::string config_path;
  DaemonConfig flags;  // values of the flags; only those given are applied
  CommandLine result;
  app.add_option("--config", config_path, "JSON configuration file (see config/skinstreamd.reference.json)");
  std::vector<std::pair<const ConfigKey*, CLI::Option*>> options;
  for (const ConfigKey& key : config_keys())
    if (key.add_flag) options.emplace_back(&key, key.add_flag(app, flags)->description(key.flag_help));
  app.add_flag("--print-config", result.print_config, "print the effective configuration as JSON and exit");
  app.add_flag("--print-reference-config", result.print_reference_config,
               "print config/skinstreamd.reference.json as the key table makes it, and exit");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    out_exit_code = app.exit(e);
    return std::nullopt;
  }
  DaemonConfig& c = result.config;
  if (!config_path.empty()) c = load_config_file(config_path);
  // A source given on the command line replaces the file's (several on the command line: validate() refuses).
  const bool source_given = std::any_of(
      options.begin(), options.end(), [](const auto& o) { return o.first->source && o.second->count() > 0; });
  const DaemonConfig defaults;
  for (const auto& [key, option] : options) {
    if (option->count() > 0)
      key->take_flag(flags, c);
    else if (key->source && source_given)
      key->take_flag(defaults, c);  // none
  }
  validate(c);
  out_exit_code = 0;
  return result;
}

}  // namespace skinstream::server
