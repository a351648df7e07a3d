#pragma once
// skinstreamd's configuration: a JSON file (config/skinstreamd.reference.json documents every
// key), then command-line flags on top. Everything the daemon is told comes through here.

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace skinstream::server {

// A subject's name is at most this long (as in a subscriber's Hello, docs/subscriber-protocol.md).
inline constexpr size_t kMaxSubjectNameBytes = 256;

// One subject the daemon serves: its subject file, and the capture system's subject it follows.
struct SubjectConfig {
  std::string name;  // the source subject (Vicon subject name); empty: one actor, found by its labels
  std::string file;  // subject file (skinstream build-subject)
  bool operator==(const SubjectConfig&) const = default;
};

// "NAME=FILE" or "FILE": the form of --subject and of the "subject" key. A NAME has no '/' (so
// "dir/a=b.sks" is a file).
SubjectConfig parse_subject(const std::string& text);

struct DaemonConfig {
  std::vector<SubjectConfig> subjects;  // none = nothing to serve (an error at start)
  std::string replay;             // capture file to replay (C3D/TRC); empty = none
  std::string replay_subject;     // replay: the name of the file's one subject; empty = the file's stem
  bool loop = false;              // replay: start again at the end
  double speed = 1.0;             // replay: multiple of the capture rate
  std::string vicon;              // HOST:PORT of a Vicon DataStream server; empty = none
  bool vicon_pull = false;        // Vicon: ask for each frame instead of server push
  std::string vicon_multicast;    // GROUP:PORT (or this host's address:PORT) of Vicon UDP datagrams; empty = none
  std::string qtm;                // HOST[:PORT] of a QTM RT server (its little-endian port, 22223); empty = none
  std::string natnet;             // HOST[:PORT] of a NatNet server's command port (1510); empty = none
  std::string natnet_interface = "0.0.0.0";  // NatNet: this host's address to join the multicast group on
  std::string bind_address = "0.0.0.0";
  int http_port = 8480;           // 0 = ephemeral
  int sub_port = 8481;            // 0 = ephemeral
  std::string web_root;           // static files served at /; empty = none
  int lookahead = 0;              // frames: gap-end blend and confirmation of new relabels
  int max_frame_wait_ms = 25;     // a frame that waited this long (for the pipeline, for a subscriber) gives way to a newer one
  int deform_threads = 2;         // the pipeline thread plus deform_threads - 1 workers
  std::string deform_cpus = "auto";  // "auto", "off" or "2,3": server/pipeline/deform_cpus.h
  int deform_spin_lead_us = 1000;  // workers spin this long before a frame is due; 0 = sleep until woken
  double continuity_seconds = 1.0;
  bool use_pca = true;
  std::string ports_file;         // written as {"http":N,"sub":N} once listening
  std::string log_level = "info";
  int hello_timeout_ms = 2000;    // subscribers that say nothing get positions only
  int publish_threads = 2;        // threads writing to TCP subscribers; 0 = the io thread (server/publish/publish_threads.h)
  std::string subscriber_tcp_congestion = "reno";  // on subscriber and HTTP connections; empty = the system's (server/tcp_congestion.h)
  int subscriber_queue_frames = 32;  // per subscriber at most; max_frame_wait_ms bounds their age
  int compressed_key_interval = 10;  // frames between key frames of the compressed encoding
  int status_interval_ms = 1000;
  int status_log_seconds = 5;  // a status line per subject in the log this often (0: none)
  std::string multicast;          // GROUP:PORT: also send every frame's parameters to this IPv4 multicast group; empty = off
  std::string multicast_interface = "0.0.0.0";  // multicast: this host's address to send from; 0.0.0.0 = the system's route
  int multicast_ttl = 1;          // multicast: hops the datagrams may cross (1: this link)
  std::string multicast_key_file;  // multicast: a file whose first line is the key the datagrams are signed with; empty = unsigned
  int multicast_offer_mbit =
      20;  // multicast: the packed MeshInfo and Model offered round and round to port + 1 this fast; 0 = not
  double default_rate_hz = 120.0;  // until the source says its rate
  // What one source message may describe (vicon::DescriptionLimits); more is a malformed packet.
  int source_max_subjects = 128;
  int source_max_markers_per_subject = 1024;
  int source_max_name_bytes = 256;
  // Positions farther than this from the capture system's origin along any axis are missing (counted).
  double source_max_coordinate_m = 50.0;
  // QTM RT, NatNet and Vicon: a server that does not finish its handshake within this is left and
  // retried; one that sends no frame for source_stall_ms while streaming is "stalled" and retried (0: never).
  int source_handshake_timeout_ms = 3000;
  int source_stall_ms = 1000;
  // Who may subscribe, and how many (server/publish/subscriber_admission.h).
  int max_subscribers = 256;              // TCP and WebSocket together; 0 = no limit
  int max_subscribers_per_address = 64;   // from one remote address; 0 = no limit
  int subscriber_write_stall_ms = 10000;  // a write without progress this long closes the subscriber; 0 = never
  std::vector<std::string> allow_subscribers;  // CIDR networks subscribers may connect from; empty = any
  std::string subscriber_token;           // asked of every subscriber (Hello version 2, ?token=); empty = none
  // With a token: connections that have not given it yet, in all and from one address (0 = no limit) ...
  int max_unauthenticated_subscribers = 64;
  int max_unauthenticated_per_address = 4;
  int unauthenticated_hello_timeout_ms = 1000;  // ... and how long they have to say Hello
  // Bytes a subscriber's socket may hold not yet sent (TCP_NOTSENT_LOWAT); 0 = the system's (no limit).
  int subscriber_unsent_kb = 128;
  // The joiners' MeshInfo and Model, all together, at most this fast (Mbit/s; 0 = unpaced).
  int subscriber_join_mbit = 300;
  // Takes (server/record/take_recorder.h).
  std::string record_dir;           // empty = no recording
  bool record_always = false;       // one take from start to stop
  bool record_with_source = false;  // a take while the capture system records one (NatNet, QTM)
  int record_unlabelled = 256;      // unlabelled channels of a received take
  // The operator's control API (docs/control-api.md): a file holding its token; empty = off (unless
  // SKINSTREAM_CONTROL_TOKEN is set). Read by load_control_token (server/control/control_token.h).
  std::string control_token_file;
  // Subjects changed at run time (server/subjects/subject_changes.h).
  std::string calibration_dir;   // empty = record_dir's "calibrations", else the system's temporary folder's
  std::string calibration_mesh;  // a live calibration's body mesh when its request names none
  std::string subject_builder;   // empty = the skinstream program beside skinstreamd
};

// Thrown for a bad config file, a bad key or value, or conflicting flags: one line, says which.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Applies a JSON object's keys onto `config`. Unknown keys and wrong types are errors (typos
// would otherwise be ignored silently). `origin` names the file in messages.
void apply_json(const nlohmann::json& json, DaemonConfig& config, const std::string& origin);
DaemonConfig load_config_file(const std::string& path);  // throws ConfigError
nlohmann::json to_json(const DaemonConfig& config);
// to_json with the subscriber token left out (whether one is set, and its length, shown): what
// --print-config prints, so the token does not reach a terminal, a log or a ticket.
nlohmann::json printable(const DaemonConfig& config);
// Range and consistency checks; throws ConfigError.
void validate(const DaemonConfig& config);

// "HOST:PORT" (split at the last colon; a port of 1-65535 in digits): the form of the vicon and
// vicon_multicast keys. nullopt for anything else.
struct HostPort {
  std::string host;
  uint16_t port = 0;
};
std::optional<HostPort> parse_host_port(const std::string& text);
// "HOST" (with `default_port`) or "HOST:PORT" as parse_host_port: the form of the qtm and natnet keys.
std::optional<HostPort> parse_host_with_port(const std::string& text, uint16_t default_port);

struct CommandLine {
  DaemonConfig config;
  bool print_config = false;
  bool print_reference_config = false;  // config/skinstreamd.reference.json, from the key table
};
// Parses argv: --config FILE first, then every flag given overrides it. Throws ConfigError for
// config problems; CLI11 parse errors are returned as an exit code via `out_exit_code`.
std::optional<CommandLine> parse_command_line(int argc, const char* const* argv, int& out_exit_code);

}  // namespace skinstream::server
