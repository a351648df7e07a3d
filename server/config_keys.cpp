#include "server/config_keys.h"

#include <arpa/inet.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <type_traits>

#include "protocol/subscriber/subscriber_stream.h"
#include "server/pipeline/deform_cpus.h"
#include "server/publish/subscriber_network.h"
#include "server/tcp_congestion.h"

namespace skinstream::server {
namespace {

// Names below are the table's own: a unity build compiles this file together with config.cpp.
template <typename T>
void read_key_value(const nlohmann::json& value, const std::string& name, T& out, const std::string& origin) {
  try {
    out = value.get<T>();
  } catch (const nlohmann::json::exception&) {
    throw ConfigError(origin + ": key \"" + name + "\" has the wrong type (" + value.type_name() + ")");
  }
}

SubjectConfig subject_from_json(const nlohmann::json& json, const std::string& origin) {
  SubjectConfig subject;
  if (json.is_object()) {
    for (const auto& [key, value] : json.items())
      if (key != "name" && key != "file")
        throw ConfigError(origin + ": unknown key \"" + key + "\" in a subject (name, file)");
    if (json.contains("name")) read_key_value(json["name"], "name", subject.name, origin);
    if (json.contains("file")) read_key_value(json["file"], "file", subject.file, origin);
  } else if (json.is_string()) {
    subject = parse_subject(json.get<std::string>());
  } else {
    throw ConfigError(origin + ": a subject is {\"name\": NAME, \"file\": FILE} or \"NAME=FILE\"");
  }
  return subject;
}

std::string subjects_problem(const DaemonConfig& c) {
  for (size_t i = 0; i < c.subjects.size(); ++i) {
    const SubjectConfig& subject = c.subjects[i];
    if (subject.file.empty()) return "subject \"" + subject.name + "\" has no file";
    if (subject.name.size() > kMaxSubjectNameBytes) return "a subject name is at most 256 bytes";
    if (subject.name.empty() && c.subjects.size() > 1)
      return "with several subjects each follows a named one: --subject NAME=FILE (" + subject.file +
             " has no name)";
    for (size_t j = 0; j < i; ++j)
      if (c.subjects[j].name == subject.name) return "subject \"" + subject.name + "\" is given twice";
  }
  return "";
}

bool is_ipv4_text(const std::string& text) {
  in_addr address{};
  return inet_pton(AF_INET, text.c_str(), &address) == 1;
}

auto between(int min, int max) {
  return [min, max](int value) { return value >= min && value <= max; };
}
auto at_least(int min) {
  return [min](int value) { return value >= min; };
}
const std::vector<std::string> kLogLevels = {"trace", "debug", "info", "warn", "error", "critical", "off"};
auto one_of(const std::vector<std::string>& choices) {
  return [&choices](const std::string& value) {
    return std::find(choices.begin(), choices.end(), value) != choices.end();
  };
}

// A key that is one DaemonConfig member, read, printed and given on the command line as it is;
// `allowed` (with its text, "NAME must be ...") checks its value.
template <typename T>
ConfigKey bound(T DaemonConfig::*member, ConfigKey key,
                std::type_identity_t<std::function<bool(const T&)>> allowed = {},
                const std::string& allowed_text = "") {
  const std::string name = key.name;
  key.read = [member, name](const nlohmann::json& object, DaemonConfig& c, const std::string& origin) {
    read_key_value(object.at(name), name, c.*member, origin);
  };
  key.write = [member](const DaemonConfig& c) { return nlohmann::json(c.*member); };
  if (allowed)
    key.problem = [member, name, allowed, allowed_text](const DaemonConfig& c) {
      return allowed(c.*member) ? std::string() : name + " must be " + allowed_text;
    };
  if (!key.flag.empty()) {
    const std::string flag = key.flag;
    key.add_flag = [member, flag](CLI::App& app, DaemonConfig& flags) -> CLI::Option* {
      if constexpr (std::is_same_v<T, bool>)
        return app.add_flag(flag, flags.*member);
      else
        return app.add_option(flag, flags.*member);
    };
    key.take_flag = [member](const DaemonConfig& flags, DaemonConfig& c) { c.*member = flags.*member; };
  }
  return key;
}

std::vector<ConfigKey> make_config_keys() {
  return {
      // Each key's comment is laid out line for line as in the reference file.
      // clang-format off
      ConfigKey{
          .name = "subjects",
          .flag = "--subject",
          .flag_help =
              "subject file (skinstream build-subject), or NAME=FILE to follow the capture system's subject "
              "NAME; repeat for several subjects",
          .problem = subjects_problem,
          .doc =
        "The subjects to serve, each a subject file from `skinstream build-subject` (with --mesh for a\n"
        "deformation model; without one, only markers are published and MeshInfo has V = 0) and the\n"
        "name of the capture system's subject it follows (the Vicon subject name): its labels are\n"
        "matched within that subject only, so several actors wearing one marker template never mix.\n"
        "At least one is required. Flag: --subject NAME=FILE, repeated for several subjects.\n"
        "  \"subjects\": [{\"name\": \"Actor1\", \"file\": \"actor1.sksubj\"},\n"
        "               {\"name\": \"Actor2\", \"file\": \"actor2.sksubj\"}]\n"
        "One actor may be given as \"subject\": \"FILE\" (flag --subject FILE): it then follows every\n"
        "source subject that carries its marker labels (the one subject of a stream, or several that\n"
        "split one body). \"subject\": \"NAME=FILE\" names it. A named subject absent from the stream is\n"
        "reported (log, /health, Status) and waited for; subjects may come and go mid-stream. Each\n"
        "subject has its own fill, deformation and hand-off; a subscriber names the one it wants in\n"
        "its Hello (version 2; version 1 subscribers get the first).",
          .read =
              [](const nlohmann::json& object, DaemonConfig& c, const std::string& origin) {
                const nlohmann::json& list = object.at("subjects");
                if (!list.is_array())
                  throw ConfigError(origin +
                                    ": key \"subjects\" must be a list of {\"name\": NAME, \"file\": FILE}");
                c.subjects.clear();
                for (const nlohmann::json& subject : list)
                  c.subjects.push_back(subject_from_json(subject, origin));
              },
          .write =
              [](const DaemonConfig& c) {
                nlohmann::json subjects = nlohmann::json::array();
                for (const SubjectConfig& s : c.subjects)
                  subjects.push_back({{"name", s.name}, {"file", s.file}});
                return subjects;
              },
          .add_flag =
              [](CLI::App& app, DaemonConfig& flags) {
                auto take_all = [&flags](const std::vector<std::string>& specs) {
                  flags.subjects.clear();
                  for (const std::string& spec : specs) flags.subjects.push_back(parse_subject(spec));
                };
                return app.add_option_function<std::vector<std::string>>("--subject", take_all)
                    ->expected(1)
                    ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
              },
          .take_flag = [](const DaemonConfig& flags, DaemonConfig& c) { c.subjects = flags.subjects; }},
      // One subject, "FILE" or "NAME=FILE" (its documentation is that of "subjects"): read, never printed.
      ConfigKey{.name = "subject",
                .read =
                    [](const nlohmann::json& object, DaemonConfig& c, const std::string& origin) {
                      if (object.contains("subjects"))
                        throw ConfigError(origin +
                                          ": give \"subject\" (one) or \"subjects\" (a list), not both");
                      const nlohmann::json& value = object.at("subject");
                      if (!value.is_string())
                        throw ConfigError(origin + ": key \"subject\" has the wrong type (" +
                                          value.type_name() + ")");
                      c.subjects = {parse_subject(value.get<std::string>())};
                    }},
      bound(&DaemonConfig::replay,
            {.name = "replay", .flag = "--replay", .new_group = true, .source = true,
             .flag_help = "replay a capture file (C3D/TRC) as the source",
             .doc =
        "Source: either a capture file to replay (C3D or TRC; flag --replay), one subject ..."}),
      bound(&DaemonConfig::replay_subject,
            {.name = "replay_subject", .flag = "--replay-subject",
             .flag_help = "replay: the name of the file's subject (default: the file's stem)",
             .doc =
        "... named this (flag --replay-subject; empty: the file's name without its extension) ..."}),
      bound(&DaemonConfig::loop,
            {.name = "loop", .flag = "--loop",
             .flag_help = "replay: start again at the end",
             .doc =
        "... started again at its end (flag --loop) ..."}),
      bound(&DaemonConfig::speed,
            {.name = "speed", .flag = "--speed",
             .flag_help = "replay: multiple of the capture rate",
             .doc =
        "... at this multiple of its capture rate (flag --speed; (0, 100])."},
            [](double v) { return v > 0 && v <= 100; }, "in (0, 100]"),
      bound(&DaemonConfig::vicon,
            {.name = "vicon", .flag = "--vicon", .source = true,
             .flag_help = "Vicon DataStream server HOST:PORT as the source",
             .problem = [](const DaemonConfig& c) -> std::string {
               if (c.vicon.empty() || parse_host_port(c.vicon)) return "";
               return "vicon must be HOST:PORT with a port of 1-65535 (Vicon's default is 801), not \"" +
                      c.vicon + "\"";
             },
             .doc =
        "... or a Vicon DataStream server \"HOST:PORT\" (flag --vicon; Nexus/Tracker/Shogun listen on\n"
        "801, skinstream-replay on the port it prints). Its subjects' marker names are matched to the\n"
        "subject file's. When the server is unreachable or goes away the daemon keeps serving, reports\n"
        "\"disconnected\" (Status messages, /health) and reconnects after 0.25 s, doubling to 5 s; one\n"
        "that stops sending frames is \"stalled\" and reconnected (source_stall_ms)."}),
      bound(&DaemonConfig::vicon_pull,
            {.name = "vicon_pull", .flag = "--vicon-pull",
             .flag_help = "Vicon: ask for each frame (ClientPull) instead of the server pushing them",
             .doc =
        "Vicon: request each frame (ClientPull) instead of the server pushing every frame\n"
        "(ServerPush, the default) (flag --vicon-pull)."}),
      bound(&DaemonConfig::vicon_multicast,
            {.name = "vicon_multicast", .flag = "--vicon-multicast", .source = true,
             .flag_help = "receive Vicon DataStream UDP datagrams sent to GROUP:PORT as the source",
             .problem = [](const DaemonConfig& c) -> std::string {
               if (c.vicon_multicast.empty() || parse_host_port(c.vicon_multicast)) return "";
               return "vicon_multicast must be GROUP:PORT with a port of 1-65535 (Vicon's default is 44801), "
                      "not \"" +
                      c.vicon_multicast + "\"";
             },
             .doc =
        "... or the Vicon DataStream's UDP datagrams sent to \"GROUP:PORT\" (flag --vicon-multicast;\n"
        "Vicon's default port is 44801; a unicast address of this host works too). Receive only: the\n"
        "server must already be sending (a client asked it with StartMulticastSender, or\n"
        "skinstream-replay --multicast). \"disconnected\" after 1 s without a frame."}),
      bound(&DaemonConfig::qtm,
            {.name = "qtm", .flag = "--qtm", .source = true,
             .flag_help = "Qualisys QTM RT server HOST[:PORT] as the source (little-endian port, 22223)",
             .problem = [](const DaemonConfig& c) -> std::string {
               if (c.qtm.empty() || parse_host_with_port(c.qtm, 22223)) return "";
               return "qtm must be HOST or HOST:PORT with a port of 1-65535 (QTM's little-endian port is "
                      "22223), not \"" +
                      c.qtm + "\"";
             },
             .doc =
        "... or a Qualisys QTM RT server \"HOST\" or \"HOST:PORT\" (flag --qtm): QTM's little-endian port,\n"
        "its base port + 1 (22223 when the base port is 22222). Labels are grouped into subjects by\n"
        "their prefix before the first '_' (\"Actor1_LFHD\"). Reconnects as for Vicon."}),
      bound(&DaemonConfig::natnet,
            {.name = "natnet", .flag = "--natnet", .source = true,
             .flag_help = "OptiTrack NatNet server HOST[:PORT] as the source (command port, 1510)",
             .problem = [](const DaemonConfig& c) -> std::string {
               if (c.natnet.empty() || parse_host_with_port(c.natnet, 1510)) return "";
               return "natnet must be HOST or HOST:PORT with a port of 1-65535 (the command port is 1510), "
                      "not \"" +
                      c.natnet + "\"";
             },
             .doc =
        "... or an OptiTrack NatNet server \"HOST\" or \"HOST:PORT\" (flag --natnet): Motive's command port\n"
        "(1510). Multicast or unicast as the server says; each marker set is a subject, metres become\n"
        "mm; the rate is counted from the frames' timestamps over windows of a second or more.\n"
        "\"stalled\" after source_stall_ms without a frame; reconnects as for Vicon."}),
      bound(&DaemonConfig::natnet_interface,
            {.name = "natnet_interface", .flag = "--natnet-interface",
             .flag_help = "NatNet: this host's IPv4 address to join the multicast group on",
             .problem = [](const DaemonConfig& c) -> std::string {
               if (is_ipv4_text(c.natnet_interface)) return "";
               return "natnet_interface must be an IPv4 address of this host, not \"" + c.natnet_interface +
                      "\"";
             },
             .doc =
        "NatNet: this host's IPv4 address to join the multicast group on (flag --natnet-interface;\n"
        "0.0.0.0 lets the system choose; name the stage network's address on hosts with several)."}),
      bound(&DaemonConfig::bind_address,
            {.name = "bind_address", .flag = "--bind", .new_group = true,
             .flag_help = "address to listen on",
             .doc =
        "Address both ports listen on (flag --bind)."}),
      bound(&DaemonConfig::http_port,
            {.name = "http_port", .flag = "--http-port",
             .flag_help = "HTTP/WebSocket port (0 = ephemeral)",
             .doc =
        "HTTP port: /health, /metrics, WebSocket subscribers at /stream, static files (flag\n"
        "--http-port; 0 = any free port, see ports_file)."},
            between(0, 65535), "0-65535"),
      bound(&DaemonConfig::sub_port,
            {.name = "sub_port", .flag = "--sub-port",
             .flag_help = "TCP subscriber port (0 = ephemeral)",
             .doc =
        "TCP subscriber port, docs/subscriber-protocol.md (flag --sub-port; 0 = any free port)."},
            between(0, 65535), "0-65535"),
      bound(&DaemonConfig::web_root,
            {.name = "web_root", .flag = "--web-root",
             .flag_help = "folder of static files served at /",
             .doc =
        "Folder served at / (index.html), e.g. clients/web; empty = no static files (flag --web-root)."}),
      bound(&DaemonConfig::ports_file,
            {.name = "ports_file", .flag = "--ports-file",
             .flag_help = "write {\"http\":N,\"sub\":N} here once listening",
             .doc =
        "Written as {\"http\":N,\"sub\":N} once both ports listen (flag --ports-file)."}),
      bound(&DaemonConfig::lookahead,
            {.name = "lookahead", .flag = "--lookahead", .new_group = true,
             .flag_help = "lookahead in frames: the gap-end blend and the confirmation of new relabels "
                          "(adds latency)",
             .doc =
        "Lookahead in frames: better gap ends and new relabels confirmed over it, lookahead / rate seconds\n"
        "of latency (flag --lookahead; 0-240)."},
            between(0, 240), "0-240 frames"),
      bound(&DaemonConfig::max_frame_wait_ms,
            {.name = "max_frame_wait_ms", .flag = "--max-frame-wait-ms",
             .flag_help = "a frame that waited this long for the pipeline or a subscriber gives way to a "
                          "newer one (0 = newest frame wins)",
             .doc =
        "A frame that has waited this long for the pipeline, or in a subscriber's queue since it was\n"
        "published, gives way to a newer one (counted: frames_dropped, per subscriber dropped), so\n"
        "a pipeline or a subscriber that falls behind adds at most this much latency, while frames\n"
        "that arrive together (a burst after the source or the network held them) all get through\n"
        "within it. Up to 32 frames wait for the pipeline; a longer burst loses its oldest at once\n"
        "(flag --max-frame-wait-ms; 0-1000; 0 = the newest frame always wins)."},
            between(0, 1000), "0-1000"),
      bound(&DaemonConfig::deform_threads,
            {.name = "deform_threads", .flag = "--deform-threads",
             .flag_help = "threads deforming the mesh (pipeline thread included)",
             .doc =
        "Threads deforming each subject's mesh: its pipeline thread plus deform_threads - 1 workers\n"
        "(flag --deform-threads; 1-64). Every subject has its own."},
            between(1, 64), "1-64"),
      bound(&DaemonConfig::deform_cpus,
            {.name = "deform_cpus", .flag = "--deform-cpus",
             .flag_help = "CPUs of the deform threads: auto, off, or a list such as 2,3",
             .problem = [](const DaemonConfig& c) { return deform_cpus_problem(c.deform_cpus); },
             .doc =
        "CPUs of the deform threads, each subject's pipeline thread first, subject after subject\n"
        "(flag --deform-cpus): \"auto\" pins them to the last subjects x deform_threads CPUs this\n"
        "process may run on when there are that many (else none), \"off\" leaves them to the OS,\n"
        "\"2,3\" names them (subjects x deform_threads of them). Pinned, the OS cannot stack a\n"
        "pipeline thread and its worker on one core (measured in the README)."}),
      bound(&DaemonConfig::deform_spin_lead_us,
            {.name = "deform_spin_lead_us", .flag = "--deform-spin-lead-us",
             .flag_help = "deform workers spin this long before a frame is due (0 = sleep until woken)",
             .doc =
        "Deform workers start to spin this many microseconds before the next frame is due (from\n"
        "the interval between frames), so the OS's wake-up is not paid inside the frame; 0 = sleep\n"
        "until woken. CPU for latency: see the README (flag --deform-spin-lead-us; 0-1000000)."},
            between(0, 1'000'000), "0-1000000"),
      bound(&DaemonConfig::continuity_seconds,
            {.name = "continuity_seconds",
             .doc =
        "Gap-start continuity decay in seconds (as `skinstream fill --continuity-seconds`; 0 = off)."},
            [](double v) { return v >= 0; }, ">= 0"),
      bound(&DaemonConfig::use_pca,
            {.name = "use_pca",
             .doc =
        "false: rigid neighbour estimates only (as `skinstream fill --no-pca`)."}),
      bound(&DaemonConfig::default_rate_hz,
            {.name = "default_rate_hz",
             .doc =
        "Capture rate assumed until the source reports its own, Hz."},
            [](double v) { return v > 0; }, "> 0"),
      bound(&DaemonConfig::source_max_subjects,
            {.name = "source_max_subjects",
             .doc =
        "What one message of the source may describe; a packet beyond these is malformed (counted\n"
        "and logged as bad input: the TCP source reconnects, a datagram is dropped), so a broken or\n"
        "hostile source cannot make the daemon decode, remember or log without end. Subjects in one\n"
        "Vicon packet (1-4096) ..."},
            between(1, 4096), "1-4096"),
      bound(&DaemonConfig::source_max_markers_per_subject,
            {.name = "source_max_markers_per_subject",
             .doc =
        "... markers of one subject, and its segments alike (1-65536) ..."},
            between(1, 65536), "1-65536"),
      bound(&DaemonConfig::source_max_name_bytes,
            {.name = "source_max_name_bytes",
             .doc =
        "... and the bytes of one subject, segment or marker name (1-4096). Shown in /health."},
            between(1, 4096), "1-4096"),
      bound(&DaemonConfig::source_max_coordinate_m,
            {.name = "source_max_coordinate_m",
             .doc =
        "A position farther than this from the capture system's origin along any axis, metres, is\n"
        "taken as missing, as is one that is not finite, from every source (counted as bad input\n"
        "\"implausible_point\" and \"rejected_point\"); no stage is this large ((0, 1000000])."},
            [](double v) { return v > 0 && v <= 1e6; }, "in (0, 1000000]"),
      bound(&DaemonConfig::source_handshake_timeout_ms,
            {.name = "source_handshake_timeout_ms",
             .doc =
        "QTM RT, NatNet and Vicon DataStream: a server that does not finish the handshake (welcome,\n"
        "version, parameters; server info and model definitions; ObjectEnums and the first frame)\n"
        "within this many ms is left, reported \"disconnected\" with the reason and retried\n"
        "(100-600000) ..."},
            between(100, 600'000), "100-600000"),
      bound(&DaemonConfig::source_stall_ms,
            {.name = "source_stall_ms",
             .doc =
        "... and one that sends no frame for this many ms while streaming (connected, but silent) is\n"
        "reported \"stalled\" (/health, the status line, Status messages) and retried (0 = never;\n"
        "50-600000). A QTM measurement that ended (NoMoreData) is \"finished\", not stalled."},
            [](int v) { return v == 0 || (v >= 50 && v <= 600'000); }, "0 (never) or 50-600000"),
      bound(&DaemonConfig::hello_timeout_ms,
            {.name = "hello_timeout_ms", .new_group = true,
             .doc =
        "How long a new subscriber has to send Hello before it gets positions only, ms."},
            at_least(0), ">= 0"),
      bound(&DaemonConfig::subscriber_queue_frames,
            {.name = "subscriber_queue_frames",
             .doc =
        "Frames queued per subscriber at most (1-64); beyond that, or older than max_frame_wait_ms,\n"
        "the oldest gives way to the newest and the drop is counted. A stalled subscriber so holds\n"
        "only the last max_frame_wait_ms of frames."},
            between(1, 64), "1-64"),
      bound(&DaemonConfig::compressed_key_interval,
            {.name = "compressed_key_interval",
             .doc =
        "The compressed encoding sends a key frame at least this often, in frames (1-1200): the\n"
        "longest a subscriber that joined, or lost a key in its queue, waits for its first frame.\n"
        "Between keys each frame is coded as its difference from the key (docs/subscriber-protocol.md)."},
            between(1, 1200), "1-1200"),
      bound(&DaemonConfig::publish_threads,
            {.name = "publish_threads", .flag = "--publish-threads",
             .flag_help = "threads writing to TCP subscribers (0 = the io thread)",
             .doc =
        "Threads writing frames to the TCP subscribers, each subscriber on the one with the fewest\n"
        "(flag --publish-threads; 0-16; 0 = the io thread that also reads the source and serves\n"
        "HTTP). With two, the source is not read behind the writes and the median delivery to 4\n"
        "subscribers is lower; the p99 is no different on two cores (measured in the README).\n"
        "WebSocket subscribers stay on the io thread."},
            between(0, 16), "0-16"),
      bound(&DaemonConfig::subscriber_tcp_congestion,
            {.name = "subscriber_tcp_congestion", .flag = "--subscriber-tcp-congestion",
             .flag_help = "TCP congestion control of subscriber connections, e.g. reno (\"\" = the system's)",
             .problem = [](const DaemonConfig& c) -> std::string {
               const std::string& name = c.subscriber_tcp_congestion;
               if (name.empty() || is_tcp_congestion_name(name)) return "";
               return "subscriber_tcp_congestion must be empty (the system's) or a Linux congestion control "
                      "name such as reno, not \"" + name + "\"";
             },
             .doc =
        "TCP congestion control of subscriber and HTTP (WebSocket) connections (flag\n"
        "--subscriber-tcp-congestion; \"\" = the system's). Under BBR, the default on some hosts, Linux\n"
        "paces each send, so a frame leaves over a fraction of a millisecond instead of at once;\n"
        "reno does not pace and any process may choose it. On loopback with 4 subscribers delivery\n"
        "took half as long with reno or cubic as with bbr (measured in the README)."}),
      bound(&DaemonConfig::status_interval_ms,
            {.name = "status_interval_ms",
             .doc =
        "Status message period, ms (a Status is also sent on every source state change)."},
            at_least(10), ">= 10"),
      bound(&DaemonConfig::status_log_seconds,
            {.name = "status_log_seconds",
             .doc =
        "A status line per subject in the log this often, s (0: none): frames in and out and their\n"
        "rate, processing p99 over the interval, subscribers, drops."},
            between(0, 3600), "0 (none) to 3600"),
      bound(&DaemonConfig::multicast,
            {.name = "multicast", .flag = "--multicast", .new_group = true,
             .flag_help = "also send every frame's parameters to this IPv4 multicast GROUP:PORT "
                          "(docs/subscriber-protocol.md)",
             .problem = [](const DaemonConfig& c) -> std::string {
               if (c.multicast.empty()) return "";
               const std::optional<HostPort> group = parse_host_port(c.multicast);
               in_addr address{};
               if (group && inet_pton(AF_INET, group->host.c_str(), &address) == 1 &&
                   IN_MULTICAST(ntohl(address.s_addr)))
                 return c.multicast_offer_mbit > 0 && group->port == 65535
                            ? "multicast: the offer goes to the port after the frames', and " + c.multicast +
                                  " leaves none (use a lower port, or multicast_offer_mbit 0)"
                            : "";
               return "multicast must be GROUP:PORT with an IPv4 multicast group (224.0.0.0-239.255.255.255; "
                      "239.x.x.x is for a site's own use) and a port of 1-65535, not \"" + c.multicast + "\"";
             },
             .doc =
        "Also send every frame's parameters (about 7.8 kB for the demo subject, in 6 UDP datagrams of\n"
        "at most 1,400 bytes) to this IPv4 multicast group, as \"GROUP:PORT\" (flag --multicast; \"\" =\n"
        "off): one copy on the wire for any number of renderers on the LAN, which fetch MeshInfo and\n"
        "the Model over TCP (docs/subscriber-protocol.md, \"Multicast\"). The daemon then fits the parts\n"
        "every frame even with no TCP subscriber. Counted in /health (\"multicast\") and /metrics."}),
      bound(&DaemonConfig::multicast_interface,
            {.name = "multicast_interface", .flag = "--multicast-interface",
             .flag_help = "multicast: this host's IPv4 address to send from (default: the system's route)",
             .problem = [](const DaemonConfig& c) -> std::string {
               if (is_ipv4_text(c.multicast_interface)) return "";
               return "multicast_interface must be an IPv4 address of this host (0.0.0.0: the system's "
                      "route), not \"" +
                      c.multicast_interface + "\"";
             },
             .doc =
        "Multicast: this host's IPv4 address to send from (flag --multicast-interface). On a machine\n"
        "with several interfaces name the stage network's; \"0.0.0.0\" = the system's route."}),
      bound(&DaemonConfig::multicast_ttl,
            {.name = "multicast_ttl", .flag = "--multicast-ttl",
             .flag_help = "multicast: hops the datagrams may cross (default 1: this link)",
             .doc =
        "Multicast: hops the datagrams may cross (flag --multicast-ttl; 0-255). 1 keeps them on this\n"
        "link; across sites, see the README."},
            between(0, 255), "0-255"),
      bound(&DaemonConfig::multicast_key_file,
            {.name = "multicast_key_file", .flag = "--multicast-key-file",
             .flag_help = "multicast: sign every datagram (HMAC-SHA-256) with the key on this file's first "
                          "line (at least 16 bytes; receivers need the same key)",
             .doc =
        "multicast: a file whose first line (at least 16 bytes: a passphrase, or hex) is a key the\n"
        "daemon signs every datagram with (HMAC-SHA-256, 32 bytes after the fragment; flag\n"
        "--multicast-key-file). Receivers given the same key (skinstream-sub --multicast-key-file,\n"
        "client::MulticastOptions::key) take no datagram without its tag: nobody else on the LAN can\n"
        "forge a frame. \"\" = unsigned datagrams (receivers then bound what a forged one costs to\n"
        "100 ms of frames)."}),
      bound(&DaemonConfig::multicast_offer_mbit,
            {.name = "multicast_offer_mbit", .flag = "--multicast-offer-mbit",
             .flag_help = "multicast: offer the packed MeshInfo and Model round and round to PORT + 1 this fast "
                          "(Mbit/s; 0: receivers fetch them over TCP)",
             .doc =
        "Multicast: what a joining receiver needs before its first frame (the packed MeshInfo and\n"
        "Model, 0.84 MB for the demo body) is offered round and round to the group's next port (PORT\n"
        "+ 1) at this rate, Mbit/s (flag --multicast-offer-mbit; docs/subscriber-protocol.md, \"The\n"
        "offer\"). Render nodes that join together take one copy from the group instead of one each\n"
        "over TCP: at 20 a round of the demo body's takes 0.34 s. Receivers that have the Model do\n"
        "not listen to that port. The group is open to the LAN, where subscriber_token and\n"
        "allow_subscribers do not reach. 0 = no offer: receivers fetch them over TCP, through\n"
        "admission."},
            between(0, 1000), "0-1000 (0 = no offer)"),
      bound(&DaemonConfig::max_subscribers,
            {.name = "max_subscribers", .new_group = true,
             .doc =
        "Who may subscribe, and how many (docs/subscriber-protocol.md, \"Admission\"). All shown in\n"
        "/health (\"subscriber_limits\", with what was refused). A subscriber refused on the TCP port\n"
        "gets a Status saying why after its Hello (or its Hello timeout) and is closed; a WebSocket\n"
        "upgrade gets HTTP 403 (allow-list, token) or 503 (limits) with the reason in one line.\n"
        "Subscribers (TCP and WebSocket together) at most; 0 = no limit."},
            at_least(0), ">= 0 (0 = no limit)"),
      bound(&DaemonConfig::max_subscribers_per_address,
            {.name = "max_subscribers_per_address",
             .doc =
        "Subscribers from one remote address at most; 0 = no limit."},
            at_least(0), ">= 0 (0 = no limit)"),
      bound(&DaemonConfig::subscriber_write_stall_ms,
            {.name = "subscriber_write_stall_ms",
             .doc =
        "A subscriber whose write has made no progress for this long is closed and counted (a\n"
        "reader that stopped would otherwise hold its socket and the frames queued for it); checked\n"
        "at each Status period, so within status_interval_ms more. TCP counts every piece the socket\n"
        "takes as progress; WebSocket, each whole message. 0 = never."},
            at_least(0), ">= 0 (0 = never)"),
      bound(&DaemonConfig::allow_subscribers,
            {.name = "allow_subscribers",
             .problem = [](const DaemonConfig& c) -> std::string {
               for (const std::string& network : c.allow_subscribers)
                 if (!SubscriberNetwork::parse(network))
                   return "allow_subscribers: \"" + network +
                          "\" is not a network such as 10.0.0.0/8, 192.168.1.20 or fd00::/8";
               return "";
             },
             .doc =
        "Networks subscribers may connect from, as CIDR (\"10.0.0.0/8\", \"fd00::/8\"; an address alone\n"
        "is one host), checked when they connect, on both ports; /health and /metrics answer anyone.\n"
        "An IPv4 network written as IPv6 (\"::ffff:10.0.0.0/104\") is that IPv4 network (10.0.0.0/8).\n"
        "[] = any network."}),
      bound(&DaemonConfig::subscriber_token,
            {.name = "subscriber_token",
             .problem = [](const DaemonConfig& c) -> std::string {
               if (c.subscriber_token.size() <= subscriber::kMaxHelloString) return "";
               return "subscriber_token must be at most " + std::to_string(subscriber::kMaxHelloString) +
                      " bytes (Hello's token field)";
             },
             .doc =
        "A shared token every subscriber must give: in Hello version 2's token field, or on the\n"
        "WebSocket URL as ws://HOST:PORT/stream?token=... (percent-encoded); a version 1 Hello has\n"
        "none and is refused. Compared in constant time, never logged nor printed (--print-config\n"
        "says only that one is set, and its length). At most 256 bytes; \"\" = none asked."}),
      bound(&DaemonConfig::max_unauthenticated_subscribers,
            {.name = "max_unauthenticated_subscribers",
             .doc =
        "With a token, only a subscriber that gave it takes one of the max_subscribers places; until\n"
        "its Hello does, a connection holds one of these few places kept for connections without the\n"
        "token, so idle sockets cannot keep a token holder out: at most this many in all (0 = no\n"
        "limit) ..."},
            at_least(0), ">= 0 (0 = no limit)"),
      bound(&DaemonConfig::max_unauthenticated_per_address,
            {.name = "max_unauthenticated_per_address",
             .doc =
        "... and from one address (0 = no limit); beyond them a connection is refused as it\n"
        "connects (counted: refused_unauthenticated) ..."},
            at_least(0), ">= 0 (0 = no limit)"),
      bound(&DaemonConfig::unauthenticated_hello_timeout_ms,
            {.name = "unauthenticated_hello_timeout_ms",
             .doc =
        "... and one that sends no Hello within this many ms is refused and closed (10-600000)."},
            between(10, 600'000), "10-600000"),
      bound(&DaemonConfig::subscriber_unsent_kb,
            {.name = "subscriber_unsent_kb",
             .doc =
        "Bytes a subscriber's socket may hold that the network has not taken yet (Linux\n"
        "TCP_NOTSENT_LOWAT; for a reader that keeps up it stays near 0): a subscriber that stops\n"
        "reading costs the daemon this much kernel memory and copying, not the 2.6-4 MB Linux would\n"
        "otherwise give its socket. With 256 of them connecting at once, writing their MeshInfo and\n"
        "first frames took the publish threads' time from a good subscriber for 0.6 s. 0 = the\n"
        "system's (no limit)."},
            between(0, 1024 * 1024), "0-1048576 (0 = the system's)"),
      bound(&DaemonConfig::subscriber_join_mbit,
            {.name = "subscriber_join_mbit",
             .doc =
        "What joining subscribers are sent first (MeshInfo, about 1.3 MB for the demo body, and\n"
        "the Model, about 1 MB; 0.84 MB together for subscribers that read them packed) goes out\n"
        "at most this fast, all joiners together (Mbit/s), so that the frames of the subscribers\n"
        "already watching go first on the link: 60 render nodes restarting at once otherwise put\n"
        "50-140 MB on a gigabit in one burst, and the watchers' frames queue behind it. Below the\n"
        "stage link's rate less the frames' (64 parameter subscribers: about 480 Mbit/s). 0 =\n"
        "unpaced."},
            between(0, 100'000), "0-100000 (0 = unpaced)"),
      bound(&DaemonConfig::record_dir,
            {.name = "record_dir", .flag = "--record-dir", .new_group = true,
             .flag_help = "folder of the takes the daemon records (\"\" = no recording)",
             .doc =
        "Folder of the takes the daemon records (flag --record-dir; created when missing; \"\" =\n"
        "no recording). A take is, per subject, what was received (C3D and a per-frame table of\n"
        "source frame numbers, times and timecode) and what was published (the filled markers and\n"
        "each sample's status), with a take.json; started and stopped through the control API\n"
        "(docs/control-api.md) or record_always. Readable up to the last second after a crash or a\n"
        "full disk; the daemon closes interrupted takes when it starts (docs/takes.md)."}),
      bound(&DaemonConfig::record_always,
            {.name = "record_always", .flag = "--record-always",
             .flag_help = "record a take from start to stop (needs --record-dir)",
             .doc =
        "Record one take from the daemon's start to its stop, named by the UTC time (flag\n"
        "--record-always; needs record_dir)."}),
      bound(&DaemonConfig::record_with_source,
            {.name = "record_with_source", .flag = "--record-with-source",
             .flag_help = "record a take while the capture system records one (NatNet, QTM RT)",
             .doc =
        "Record a take while the capture system records one of its own (flag --record-with-source;\n"
        "needs record_dir): NatNet's frame flag (Motive recording), QTM RT's capture started and\n"
        "stopped events. Vicon DataStream does not say. A take started through the control API is\n"
        "left to the operator."}),
      bound(&DaemonConfig::record_unlabelled,
            {.name = "record_unlabelled",
             .doc =
        "Unlabelled channels of a received take (0-1024), \"*1\"..\"*N\" after the subject's markers.\n"
        "Each point goes into a channel by its trajectory: one that continues keeps its channel, a new\n"
        "one takes a channel that was empty the frame before, so a replay of the take shows the gap\n"
        "filler the same fragments it saw live. Points beyond them are counted in the take's table\n"
        "(unlabelled against unlabelled_kept), not kept. A channel costs 16 bytes a frame (1.9 kB/s\n"
        "at 120 Hz); the demo capture has up to 129 unlabelled points at once."},
            between(0, 1024), "0-1024"),
      bound(&DaemonConfig::control_token_file,
            {.name = "control_token_file", .flag = "--control-token-file", .new_group = true,
             .flag_help = "turn the control API on (POST /takes ...): the file whose first line is its token "
                          "(16-256 visible characters; not readable by every user)",
             .problem = [](const DaemonConfig& c) -> std::string {
               const std::string& path = c.control_token_file;
               const auto is_path_byte = [](unsigned char ch) { return ch >= 0x20 && ch != 0x7f; };
               if (std::all_of(path.begin(), path.end(), is_path_byte) &&
                   path.size() <= 4096)
                 return "";
               return "control_token_file must be a file's path (no line breaks nor control characters)";
             },
             .doc =
        "The operator's control API (docs/control-api.md: start and stop takes with skinstream-ctl or\n"
        "curl): a file whose first line is the token every control request must carry as\n"
        "\"Authorization: Bearer TOKEN\" (16-256 visible ASCII characters). The file must not be\n"
        "readable by every user (chmod 600): the daemon refuses to start otherwise. Instead of a file\n"
        "the token may be in the environment variable SKINSTREAM_CONTROL_TOKEN (not both); never on the\n"
        "command line, where ps shows it. Neither = the control API is off (its paths answer 404).\n"
        "Wrong tokens are counted and rate-limited per address; the token is never logged nor printed."}),
      bound(&DaemonConfig::calibration_dir,
            {.name = "calibration_dir", .new_group = true,
             .doc =
        "Folder of the live calibrations (POST /subjects/NAME/calibration): each one's range of motion\n"
        "(C3D), the subject file built from it, the builder's report and log. \"\" = \"calibrations\" in\n"
        "record_dir, or without one skinstream-calibrations in the system's temporary folder."}),
      bound(&DaemonConfig::calibration_mesh,
            {.name = "calibration_mesh",
             .doc =
        "The body a live calibration fits to the actor when its request names none: the template (a\n"
        "MakeHuman body OBJ with its skeleton and weights beside it) or a scan of the actor, as\n"
        "`skinstream build-subject --mesh` takes it. \"\" = the request must name one for a subject\n"
        "served with a mesh."}),
      bound(&DaemonConfig::subject_builder,
            {.name = "subject_builder",
             .doc =
        "The program that builds a live calibration's subject (`PROGRAM build-subject ...`, run as a\n"
        "separate process at nice 10). \"\" = the skinstream program beside skinstreamd."}),
      bound(&DaemonConfig::log_level,
            {.name = "log_level", .flag = "--log-level", .new_group = true,
             .flag_help = "trace, debug, info, warn, error, critical, off",
             .doc =
        "trace, debug, info, warn, error, critical or off (flag --log-level)."},
            one_of(kLogLevels), "one of trace, debug, info, warn, error, critical, off")
      // clang-format on
  };
}

}  // namespace

const std::vector<ConfigKey>& config_keys() {
  static const std::vector<ConfigKey> keys = make_config_keys();
  return keys;
}

std::string reference_config() {
  std::string text =
      "// skinstreamd reference configuration: every key with its default. Comments are allowed.\n"
      "// Command-line flags override the file: skinstreamd --config FILE [flags]; --print-config shows\n"
      "// the effective result. Unknown keys are an error.\n"
      "{\n";
  const DaemonConfig defaults;
  std::vector<const ConfigKey*> printed;
  for (const ConfigKey& key : config_keys())
    if (key.write) printed.push_back(&key);
  for (size_t i = 0; i < printed.size(); ++i) {
    const ConfigKey& key = *printed[i];
    if (key.new_group && i > 0) text += "\n";
    size_t start = 0;
    while (start <= key.doc.size() && !key.doc.empty()) {
      const size_t end = std::min(key.doc.find('\n', start), key.doc.size());
      text += "  // " + key.doc.substr(start, end - start) + "\n";
      start = end + 1;
    }
    text += "  \"" + key.name + "\": " + key.write(defaults).dump() + (i + 1 < printed.size() ? ",\n" : "\n");
  }
  return text + "}\n";
}

}  // namespace skinstream::server
