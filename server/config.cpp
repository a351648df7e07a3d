#include "server/config.h"

#include "protocol/subscriber_stream.h"
#include "server/pipeline/deform_cpus.h"
#include "server/publish/subscriber_network.h"
#include "server/tcp_congestion.h"

#include <arpa/inet.h>

#include <CLI/CLI.hpp>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace skinstream::server {
namespace {

template <typename T>
void take(const nlohmann::json& json, const char* key, T& out, const std::string& origin) {
  const auto it = json.find(key);
  if (it == json.end()) return;
  try {
    out = it->get<T>();
  } catch (const nlohmann::json::exception&) {
    throw ConfigError(origin + ": key \"" + key + "\" has the wrong type (" + it->type_name() + ")");
  }
}

nlohmann::json to_json(const SubjectConfig& subject) { return {{"name", subject.name}, {"file", subject.file}}; }

SubjectConfig subject_from_json(const nlohmann::json& json, const std::string& origin) {
  SubjectConfig subject;
  if (json.is_object()) {
    for (const auto& [key, value] : json.items())
      if (key != "name" && key != "file") throw ConfigError(origin + ": unknown key \"" + key + "\" in a subject (name, file)");
    take(json, "name", subject.name, origin);
    take(json, "file", subject.file, origin);
  } else if (json.is_string()) {
    subject = parse_subject(json.get<std::string>());
  } else {
    throw ConfigError(origin + ": a subject is {\"name\": NAME, \"file\": FILE} or \"NAME=FILE\"");
  }
  return subject;
}

}  // namespace

SubjectConfig parse_subject(const std::string& text) {
  const size_t equals = text.find('=');
  if (equals == std::string::npos || equals == 0 || text.find('/') < equals) return {"", text};
  return {text.substr(0, equals), text.substr(equals + 1)};
}

void apply_json(const nlohmann::json& json, DaemonConfig& c, const std::string& origin) {
  if (!json.is_object()) throw ConfigError(origin + ": the configuration must be a JSON object");
  static const char* const kKeys[] = {"subject", "subjects", "replay", "replay_subject", "loop", "speed", "vicon", "vicon_pull",
                                      "vicon_multicast", "qtm", "natnet", "natnet_interface", "bind_address",
                                      "http_port", "sub_port", "web_root", "lookahead", "max_frame_wait_ms", "deform_threads",
                                      "deform_cpus", "deform_spin_lead_us",
                                      "continuity_seconds", "use_pca", "ports_file", "log_level", "hello_timeout_ms",
                                      "subscriber_queue_frames", "subscriber_tcp_congestion", "publish_threads", "status_interval_ms", "status_log_seconds", "default_rate_hz",
                                      "compressed_key_interval", "multicast", "multicast_interface", "multicast_ttl", "multicast_key_file", "source_max_subjects", "source_max_markers_per_subject",
                                      "source_max_name_bytes", "source_max_coordinate_m", "source_handshake_timeout_ms",
                                      "source_stall_ms", "max_subscribers", "max_subscribers_per_address",
                                      "subscriber_write_stall_ms", "allow_subscribers", "subscriber_token",
                                      "max_unauthenticated_subscribers", "max_unauthenticated_per_address",
                                      "unauthenticated_hello_timeout_ms",
                                      "subscriber_unsent_kb"};
  for (const auto& [key, value] : json.items()) {
    bool known = false;
    for (const char* k : kKeys) known = known || key == k;
    if (!known) throw ConfigError(origin + ": unknown key \"" + key + "\"");
  }
  if (json.contains("subject") && json.contains("subjects"))
    throw ConfigError(origin + ": give \"subject\" (one) or \"subjects\" (a list), not both");
  if (const auto it = json.find("subject"); it != json.end()) {
    if (!it->is_string()) throw ConfigError(origin + ": key \"subject\" has the wrong type (" + it->type_name() + ")");
    c.subjects = {parse_subject(it->get<std::string>())};
  }
  if (const auto it = json.find("subjects"); it != json.end()) {
    if (!it->is_array()) throw ConfigError(origin + ": key \"subjects\" must be a list of {\"name\": NAME, \"file\": FILE}");
    c.subjects.clear();
    for (const nlohmann::json& subject : *it) c.subjects.push_back(subject_from_json(subject, origin));
  }
  take(json, "replay", c.replay, origin);
  take(json, "replay_subject", c.replay_subject, origin);
  take(json, "loop", c.loop, origin);
  take(json, "speed", c.speed, origin);
  take(json, "vicon", c.vicon, origin);
  take(json, "vicon_pull", c.vicon_pull, origin);
  take(json, "vicon_multicast", c.vicon_multicast, origin);
  take(json, "qtm", c.qtm, origin);
  take(json, "natnet", c.natnet, origin);
  take(json, "natnet_interface", c.natnet_interface, origin);
  take(json, "bind_address", c.bind_address, origin);
  take(json, "http_port", c.http_port, origin);
  take(json, "sub_port", c.sub_port, origin);
  take(json, "web_root", c.web_root, origin);
  take(json, "lookahead", c.lookahead, origin);
  take(json, "max_frame_wait_ms", c.max_frame_wait_ms, origin);
  take(json, "deform_threads", c.deform_threads, origin);
  take(json, "deform_cpus", c.deform_cpus, origin);
  take(json, "deform_spin_lead_us", c.deform_spin_lead_us, origin);
  take(json, "continuity_seconds", c.continuity_seconds, origin);
  take(json, "use_pca", c.use_pca, origin);
  take(json, "ports_file", c.ports_file, origin);
  take(json, "log_level", c.log_level, origin);
  take(json, "hello_timeout_ms", c.hello_timeout_ms, origin);
  take(json, "subscriber_queue_frames", c.subscriber_queue_frames, origin);
  take(json, "compressed_key_interval", c.compressed_key_interval, origin);
  take(json, "subscriber_tcp_congestion", c.subscriber_tcp_congestion, origin);
  take(json, "publish_threads", c.publish_threads, origin);
  take(json, "status_interval_ms", c.status_interval_ms, origin);
  take(json, "status_log_seconds", c.status_log_seconds, origin);
  take(json, "default_rate_hz", c.default_rate_hz, origin);
  take(json, "multicast", c.multicast, origin);
  take(json, "multicast_interface", c.multicast_interface, origin);
  take(json, "multicast_ttl", c.multicast_ttl, origin);
  take(json, "multicast_key_file", c.multicast_key_file, origin);
  take(json, "source_max_subjects", c.source_max_subjects, origin);
  take(json, "source_max_markers_per_subject", c.source_max_markers_per_subject, origin);
  take(json, "source_max_name_bytes", c.source_max_name_bytes, origin);
  take(json, "source_max_coordinate_m", c.source_max_coordinate_m, origin);
  take(json, "source_handshake_timeout_ms", c.source_handshake_timeout_ms, origin);
  take(json, "source_stall_ms", c.source_stall_ms, origin);
  take(json, "max_subscribers", c.max_subscribers, origin);
  take(json, "max_subscribers_per_address", c.max_subscribers_per_address, origin);
  take(json, "subscriber_write_stall_ms", c.subscriber_write_stall_ms, origin);
  take(json, "allow_subscribers", c.allow_subscribers, origin);
  take(json, "subscriber_token", c.subscriber_token, origin);
  take(json, "max_unauthenticated_subscribers", c.max_unauthenticated_subscribers, origin);
  take(json, "max_unauthenticated_per_address", c.max_unauthenticated_per_address, origin);
  take(json, "unauthenticated_hello_timeout_ms", c.unauthenticated_hello_timeout_ms, origin);
  take(json, "subscriber_unsent_kb", c.subscriber_unsent_kb, origin);
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
  nlohmann::json subjects = nlohmann::json::array();
  for (const SubjectConfig& subject : c.subjects) subjects.push_back(to_json(subject));
  return {{"subjects", subjects},
          {"replay", c.replay},
          {"replay_subject", c.replay_subject},
          {"loop", c.loop},
          {"speed", c.speed},
          {"vicon", c.vicon},
          {"vicon_pull", c.vicon_pull},
          {"vicon_multicast", c.vicon_multicast},
          {"qtm", c.qtm},
          {"natnet", c.natnet},
          {"natnet_interface", c.natnet_interface},
          {"bind_address", c.bind_address},
          {"http_port", c.http_port},
          {"sub_port", c.sub_port},
          {"web_root", c.web_root},
          {"lookahead", c.lookahead},
          {"max_frame_wait_ms", c.max_frame_wait_ms},
          {"deform_threads", c.deform_threads},
          {"deform_cpus", c.deform_cpus},
          {"deform_spin_lead_us", c.deform_spin_lead_us},
          {"continuity_seconds", c.continuity_seconds},
          {"use_pca", c.use_pca},
          {"ports_file", c.ports_file},
          {"log_level", c.log_level},
          {"hello_timeout_ms", c.hello_timeout_ms},
          {"subscriber_queue_frames", c.subscriber_queue_frames},
          {"compressed_key_interval", c.compressed_key_interval},
          {"subscriber_tcp_congestion", c.subscriber_tcp_congestion},
          {"publish_threads", c.publish_threads},
          {"status_interval_ms", c.status_interval_ms},
          {"status_log_seconds", c.status_log_seconds},
          {"default_rate_hz", c.default_rate_hz},
          {"multicast", c.multicast},
          {"multicast_interface", c.multicast_interface},
          {"multicast_ttl", c.multicast_ttl},
          {"multicast_key_file", c.multicast_key_file},
          {"source_max_subjects", c.source_max_subjects},
          {"source_max_markers_per_subject", c.source_max_markers_per_subject},
          {"source_max_name_bytes", c.source_max_name_bytes},
          {"source_max_coordinate_m", c.source_max_coordinate_m},
          {"source_handshake_timeout_ms", c.source_handshake_timeout_ms},
          {"source_stall_ms", c.source_stall_ms},
          {"max_subscribers", c.max_subscribers},
          {"max_subscribers_per_address", c.max_subscribers_per_address},
          {"subscriber_write_stall_ms", c.subscriber_write_stall_ms},
          {"allow_subscribers", c.allow_subscribers},
          {"subscriber_token", c.subscriber_token},
          {"max_unauthenticated_subscribers", c.max_unauthenticated_subscribers},
          {"max_unauthenticated_per_address", c.max_unauthenticated_per_address},
          {"unauthenticated_hello_timeout_ms", c.unauthenticated_hello_timeout_ms},
          {"subscriber_unsent_kb", c.subscriber_unsent_kb}};
}

nlohmann::json printable(const DaemonConfig& c) {
  nlohmann::json json = to_json(c);
  if (!c.subscriber_token.empty())
    json["subscriber_token"] = "(set, " + std::to_string(c.subscriber_token.size()) + " bytes, not shown)";
  return json;
}

void validate(const DaemonConfig& c) {
  auto fail = [](const std::string& what) { throw ConfigError("configuration: " + what); };
  if (!c.replay.empty() + !c.vicon.empty() + !c.vicon_multicast.empty() + !c.qtm.empty() + !c.natnet.empty() > 1)
    fail("give one source: a replay file, a Vicon server, a Vicon multicast address, a QTM or a NatNet server");
  if (!(c.speed > 0 && c.speed <= 100)) fail("speed must be in (0, 100]");
  for (size_t i = 0; i < c.subjects.size(); ++i) {
    const SubjectConfig& subject = c.subjects[i];
    if (subject.file.empty()) fail("subject \"" + subject.name + "\" has no file");
    if (subject.name.size() > kMaxSubjectNameBytes) fail("a subject name is at most 256 bytes");
    if (subject.name.empty() && c.subjects.size() > 1)
      fail("with several subjects each follows a named one: --subject NAME=FILE (" + subject.file + " has no name)");
    for (size_t j = 0; j < i; ++j)
      if (c.subjects[j].name == subject.name) fail("subject \"" + subject.name + "\" is given twice");
  }
  if (c.http_port < 0 || c.http_port > 65535) fail("http_port must be 0-65535");
  if (c.sub_port < 0 || c.sub_port > 65535) fail("sub_port must be 0-65535");
  if (c.lookahead < 0 || c.lookahead > 240) fail("lookahead must be 0-240 frames");
  if (c.max_frame_wait_ms < 0 || c.max_frame_wait_ms > 1000) fail("max_frame_wait_ms must be 0-1000");
  if (c.deform_threads < 1 || c.deform_threads > 64) fail("deform_threads must be 1-64");
  if (const std::string problem = deform_cpus_problem(c.deform_cpus); !problem.empty()) fail(problem);
  if (c.deform_spin_lead_us < 0 || c.deform_spin_lead_us > 1'000'000) fail("deform_spin_lead_us must be 0-1000000");
  if (c.continuity_seconds < 0) fail("continuity_seconds must be >= 0");
  if (c.hello_timeout_ms < 0) fail("hello_timeout_ms must be >= 0");
  if (c.subscriber_queue_frames < 1 || c.subscriber_queue_frames > 64) fail("subscriber_queue_frames must be 1-64");
  if (c.compressed_key_interval < 1 || c.compressed_key_interval > 1200) fail("compressed_key_interval must be 1-1200");
  if (c.publish_threads < 0 || c.publish_threads > 16) fail("publish_threads must be 0-16");
  if (!c.subscriber_tcp_congestion.empty() && !is_tcp_congestion_name(c.subscriber_tcp_congestion))
    fail("subscriber_tcp_congestion must be empty (the system's) or a Linux congestion control name such as reno, not \"" +
         c.subscriber_tcp_congestion + "\"");
  if (c.status_interval_ms < 10) fail("status_interval_ms must be >= 10");
  if (c.status_log_seconds < 0 || c.status_log_seconds > 3600) fail("status_log_seconds must be 0 (none) to 3600");
  if (!(c.default_rate_hz > 0)) fail("default_rate_hz must be > 0");
  if (c.source_max_subjects < 1 || c.source_max_subjects > 4096) fail("source_max_subjects must be 1-4096");
  if (c.source_max_markers_per_subject < 1 || c.source_max_markers_per_subject > 65536)
    fail("source_max_markers_per_subject must be 1-65536");
  if (c.source_max_name_bytes < 1 || c.source_max_name_bytes > 4096) fail("source_max_name_bytes must be 1-4096");
  if (!(c.source_max_coordinate_m > 0 && c.source_max_coordinate_m <= 1e6)) fail("source_max_coordinate_m must be in (0, 1000000]");
  if (c.source_handshake_timeout_ms < 100 || c.source_handshake_timeout_ms > 600'000)
    fail("source_handshake_timeout_ms must be 100-600000");
  if (c.source_stall_ms != 0 && (c.source_stall_ms < 50 || c.source_stall_ms > 600'000))
    fail("source_stall_ms must be 0 (never) or 50-600000");
  if (c.max_subscribers < 0) fail("max_subscribers must be >= 0 (0 = no limit)");
  if (c.max_subscribers_per_address < 0) fail("max_subscribers_per_address must be >= 0 (0 = no limit)");
  if (c.subscriber_write_stall_ms < 0) fail("subscriber_write_stall_ms must be >= 0 (0 = never)");
  if (c.max_unauthenticated_subscribers < 0) fail("max_unauthenticated_subscribers must be >= 0 (0 = no limit)");
  if (c.max_unauthenticated_per_address < 0) fail("max_unauthenticated_per_address must be >= 0 (0 = no limit)");
  if (c.unauthenticated_hello_timeout_ms < 10 || c.unauthenticated_hello_timeout_ms > 600'000)
    fail("unauthenticated_hello_timeout_ms must be 10-600000");
  if (c.subscriber_unsent_kb < 0 || c.subscriber_unsent_kb > 1024 * 1024)
    fail("subscriber_unsent_kb must be 0-1048576 (0 = the system's)");
  for (const std::string& network : c.allow_subscribers)
    if (!SubscriberNetwork::parse(network))
      fail("allow_subscribers: \"" + network + "\" is not a network such as 10.0.0.0/8, 192.168.1.20 or fd00::/8");
  if (c.subscriber_token.size() > subscriber::kMaxHelloString)
    fail("subscriber_token must be at most " + std::to_string(subscriber::kMaxHelloString) + " bytes (Hello's token field)");
  static const char* const kLevels[] = {"trace", "debug", "info", "warn", "error", "critical", "off"};
  bool level_ok = false;
  for (const char* l : kLevels) level_ok = level_ok || c.log_level == l;
  if (!level_ok) fail("log_level must be one of trace, debug, info, warn, error, critical, off");
  if (!c.vicon.empty() && !parse_host_port(c.vicon))
    fail("vicon must be HOST:PORT with a port of 1-65535 (Vicon's default is 801), not \"" + c.vicon + "\"");
  if (!c.vicon_multicast.empty() && !parse_host_port(c.vicon_multicast))
    fail("vicon_multicast must be GROUP:PORT with a port of 1-65535 (Vicon's default is 44801), not \"" + c.vicon_multicast + "\"");
  if (!c.qtm.empty() && !parse_host_with_port(c.qtm, 22223))
    fail("qtm must be HOST or HOST:PORT with a port of 1-65535 (QTM's little-endian port is 22223), not \"" + c.qtm + "\"");
  if (!c.natnet.empty() && !parse_host_with_port(c.natnet, 1510))
    fail("natnet must be HOST or HOST:PORT with a port of 1-65535 (the command port is 1510), not \"" + c.natnet + "\"");
  in_addr address{};
  if (!c.multicast.empty()) {
    const std::optional<HostPort> group = parse_host_port(c.multicast);
    if (!group || inet_pton(AF_INET, group->host.c_str(), &address) != 1 || !IN_MULTICAST(ntohl(address.s_addr)))
      fail("multicast must be GROUP:PORT with an IPv4 multicast group (224.0.0.0-239.255.255.255; 239.x.x.x is for a site's own use) "
           "and a port of 1-65535, not \"" + c.multicast + "\"");
  }
  if (inet_pton(AF_INET, c.multicast_interface.c_str(), &address) != 1)
    fail("multicast_interface must be an IPv4 address of this host (0.0.0.0: the system's route), not \"" + c.multicast_interface + "\"");
  if (c.multicast_ttl < 0 || c.multicast_ttl > 255) fail("multicast_ttl must be 0-255");
  if (inet_pton(AF_INET, c.natnet_interface.c_str(), &address) != 1) fail("natnet_interface must be an IPv4 address of this host, not \"" + c.natnet_interface + "\"");
}

std::optional<HostPort> parse_host_port(const std::string& text) {
  const size_t colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0) return std::nullopt;
  const std::string port = text.substr(colon + 1);
  if (port.empty() || port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;
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
  CLI::App app{"skinstreamd: live marker frames in, gap-filled deforming skin meshes out to every subscriber"};
  std::string config_path;
  DaemonConfig flags;  // values of the flags; only those given are applied
  CommandLine result;
  app.add_option("--config", config_path, "JSON configuration file (see config/skinstreamd.reference.json)");
  std::vector<std::string> subject_specs;
  auto* subject = app.add_option("--subject", subject_specs,
                                 "subject file (skinstream build-subject), or NAME=FILE to follow the capture system's subject NAME; "
                                 "repeat for several subjects")
                      ->expected(1)
                      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  auto* replay = app.add_option("--replay", flags.replay, "replay a capture file (C3D/TRC) as the source");
  auto* replay_subject = app.add_option("--replay-subject", flags.replay_subject,
                                        "replay: the name of the file's subject (default: the file's stem)");
  auto* loop = app.add_flag("--loop", flags.loop, "replay: start again at the end");
  auto* speed = app.add_option("--speed", flags.speed, "replay: multiple of the capture rate");
  auto* vicon = app.add_option("--vicon", flags.vicon, "Vicon DataStream server HOST:PORT as the source");
  auto* vicon_pull = app.add_flag("--vicon-pull", flags.vicon_pull, "Vicon: ask for each frame (ClientPull) instead of the server pushing them");
  auto* vicon_multicast = app.add_option("--vicon-multicast", flags.vicon_multicast,
                                         "receive Vicon DataStream UDP datagrams sent to GROUP:PORT as the source");
  auto* qtm = app.add_option("--qtm", flags.qtm, "Qualisys QTM RT server HOST[:PORT] as the source (little-endian port, 22223)");
  auto* natnet = app.add_option("--natnet", flags.natnet, "OptiTrack NatNet server HOST[:PORT] as the source (command port, 1510)");
  auto* natnet_interface = app.add_option("--natnet-interface", flags.natnet_interface,
                                          "NatNet: this host's IPv4 address to join the multicast group on");
  auto* multicast = app.add_option("--multicast", flags.multicast,
                                   "also send every frame's parameters to this IPv4 multicast GROUP:PORT (docs/subscriber-protocol.md)");
  auto* multicast_interface = app.add_option("--multicast-interface", flags.multicast_interface,
                                             "multicast: this host's IPv4 address to send from (default: the system's route)");
  auto* multicast_ttl = app.add_option("--multicast-ttl", flags.multicast_ttl, "multicast: hops the datagrams may cross (default 1: this link)");
  auto* multicast_key_file = app.add_option("--multicast-key-file", flags.multicast_key_file,
                                            "multicast: sign every datagram (HMAC-SHA-256) with the key on this file's first line "
                                            "(at least 16 bytes; receivers need the same key)");
  auto* bind = app.add_option("--bind", flags.bind_address, "address to listen on");
  auto* http_port = app.add_option("--http-port", flags.http_port, "HTTP/WebSocket port (0 = ephemeral)");
  auto* sub_port = app.add_option("--sub-port", flags.sub_port, "TCP subscriber port (0 = ephemeral)");
  auto* web_root = app.add_option("--web-root", flags.web_root, "folder of static files served at /");
  auto* lookahead = app.add_option("--lookahead", flags.lookahead, "lookahead in frames: the gap-end blend and the confirmation of new relabels (adds latency)");
  auto* max_wait = app.add_option("--max-frame-wait-ms", flags.max_frame_wait_ms,
                                  "a frame that waited this long for the pipeline or a subscriber gives way to a newer one "
                                  "(0 = newest frame wins)");
  auto* threads = app.add_option("--deform-threads", flags.deform_threads, "threads deforming the mesh (pipeline thread included)");
  auto* cpus = app.add_option("--deform-cpus", flags.deform_cpus, "CPUs of the deform threads: auto, off, or a list such as 2,3");
  auto* spin_lead = app.add_option("--deform-spin-lead-us", flags.deform_spin_lead_us,
                                   "deform workers spin this long before a frame is due (0 = sleep until woken)");
  auto* publish_threads = app.add_option("--publish-threads", flags.publish_threads,
                                         "threads writing to TCP subscribers (0 = the io thread)");
  auto* tcp_congestion = app.add_option("--subscriber-tcp-congestion", flags.subscriber_tcp_congestion,
                                        "TCP congestion control of subscriber connections, e.g. reno (\"\" = the system's)");
  auto* ports_file = app.add_option("--ports-file", flags.ports_file, "write {\"http\":N,\"sub\":N} here once listening");
  auto* log_level = app.add_option("--log-level", flags.log_level, "trace, debug, info, warn, error, critical, off");
  app.add_flag("--print-config", result.print_config, "print the effective configuration as JSON and exit");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    out_exit_code = app.exit(e);
    return std::nullopt;
  }
  DaemonConfig& c = result.config;
  if (!config_path.empty()) c = load_config_file(config_path);
  auto given = [](const CLI::Option* o) { return o->count() > 0; };
  if (given(subject)) {
    c.subjects.clear();
    for (const std::string& spec : subject_specs) c.subjects.push_back(parse_subject(spec));
  }
  if (given(replay_subject)) c.replay_subject = flags.replay_subject;
  // A source given on the command line replaces the file's (several on the command line: validate() refuses).
  if (given(replay) || given(vicon) || given(vicon_multicast) || given(qtm) || given(natnet)) {
    c.replay = given(replay) ? flags.replay : std::string();
    c.vicon = given(vicon) ? flags.vicon : std::string();
    c.vicon_multicast = given(vicon_multicast) ? flags.vicon_multicast : std::string();
    c.qtm = given(qtm) ? flags.qtm : std::string();
    c.natnet = given(natnet) ? flags.natnet : std::string();
  }
  if (given(natnet_interface)) c.natnet_interface = flags.natnet_interface;
  if (given(multicast)) c.multicast = flags.multicast;
  if (given(multicast_interface)) c.multicast_interface = flags.multicast_interface;
  if (given(multicast_ttl)) c.multicast_ttl = flags.multicast_ttl;
  if (given(multicast_key_file)) c.multicast_key_file = flags.multicast_key_file;
  if (given(loop)) c.loop = flags.loop;
  if (given(speed)) c.speed = flags.speed;
  if (given(vicon_pull)) c.vicon_pull = flags.vicon_pull;
  if (given(bind)) c.bind_address = flags.bind_address;
  if (given(http_port)) c.http_port = flags.http_port;
  if (given(sub_port)) c.sub_port = flags.sub_port;
  if (given(web_root)) c.web_root = flags.web_root;
  if (given(lookahead)) c.lookahead = flags.lookahead;
  if (given(max_wait)) c.max_frame_wait_ms = flags.max_frame_wait_ms;
  if (given(threads)) c.deform_threads = flags.deform_threads;
  if (given(cpus)) c.deform_cpus = flags.deform_cpus;
  if (given(spin_lead)) c.deform_spin_lead_us = flags.deform_spin_lead_us;
  if (given(publish_threads)) c.publish_threads = flags.publish_threads;
  if (given(tcp_congestion)) c.subscriber_tcp_congestion = flags.subscriber_tcp_congestion;
  if (given(ports_file)) c.ports_file = flags.ports_file;
  if (given(log_level)) c.log_level = flags.log_level;
  validate(c);
  out_exit_code = 0;
  return result;
}

}  // namespace skinstream::server
