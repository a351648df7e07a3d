#pragma once
// skinstream-bench's command line, parsed into one struct so a run can be started (and tested)
// without it.
#include <optional>
#include <string>

#include "clients/bench/hostile_waves.h"
#include "clients/bench/replay_engine.h"
#include "skinstream/client.h"

namespace skinstream::bench {

struct BenchOptions {
  double seconds = 10;
  int subscribers = 1;
  std::string recording = "replay_data/cmu/85_12.c3d";
  std::string subject;             // the subject file (required)
  std::string vicon_subject_name;  // the replay's subject name (default: the recording's file name)
  CaptureProtocol protocol = CaptureProtocol::Vicon;  // what the replay speaks to the daemon
  // NatNet: the replay's timestamps as a real capture clock stamps them (0: exact).
  double natnet_timestamp_jitter_us = 0.0;
  double natnet_clock_hz = 0.0;
  int subjects = 1;                  // actors: the recording streamed this many times, apart
  double subject_spacing_mm = 3000;  // how far apart along x
  // What the subscribers ask for and do with it.
  client::Encoding encoding = client::Encoding::Float;
  bool normals = false;
  bool decode = false;  // decode (and evaluate) each frame as a renderer would, on this machine's CPU
  bool paced = false;
  bool plain_first_contact = false;  // MeshInfo and the Model asked for plain, not packed
  // The daemon's threads and sockets (unset: its defaults).
  int deform_threads = 2;
  std::string deform_cpus;
  int deform_spin_lead_us = -1;
  int publish_threads = -1;
  std::optional<std::string> subscriber_tcp_congestion;
  std::string replay_tcp_congestion;
  // 0: loopback. Otherwise the daemon runs in a network namespace behind a veth pair shaped to
  // this rate, its subscribers and the replay outside.
  int link_mbit = 0;
  // The soak: hostile peers connect and leave in waves while the subscribers measure (loopback only).
  bool hostile_waves = false;
  int wave_seconds = 60, calm_seconds = 60;
  HostilePeers hostile_peers;
  // Render nodes restarting together: this many more subscribers connect at once, join_after
  // seconds into the window, while the first ones watch (their figures are the report's; the
  // joiners' are apart, in "join_wave").
  int join_wave = 0;
  std::string daemon_config;  // skinstreamd --config (keys without a flag, e.g. subscriber_join_mbit)
  double join_after_seconds = 3.0;
  // The joiners' threads at this nice level: render nodes are other machines on a stage, and on
  // this one their unpacking competes with the daemon for the same cores (0: as the watchers).
  int joiner_nice = 0;
  // The joiners under SCHED_IDLE instead: sixty threads at nice 19 still weigh about one thread
  // at nice 0 with the kernel, and took the watchers' and the replay's cores for 40-90 ms as they
  // joined; idle ones take only what nothing else wants.
  bool joiner_idle = false;
  // The joiners as skinstream-sub processes (as render nodes are programs of their own) instead
  // of threads of this one.
  bool joiner_processes = false;
  // --join-wave: the joiners take the parameters from the daemon's multicast group
  // (GROUP:PORT; over --link-mbit's link), MeshInfo and the Model from its offer at this rate
  // (0: no offer, over TCP).
  std::string joiner_multicast;
  int multicast_offer_mbit = 20;
  // Recording A/B in one run: a take starts and stops every this many seconds through the control
  // API (0: off); the report splits the subscribers' figures by whether a take was recording.
  double record_ab_seconds = 0.0;
  bool json = false;
};

// Parses argv; returns the exit code to leave with instead (after --help, or a usage error
// already printed), or nothing when the run should go ahead.
std::optional<int> parse_bench_options(int argc, char** argv, BenchOptions& options);

}  // namespace skinstream::bench
