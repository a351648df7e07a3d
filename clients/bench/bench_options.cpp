#include "clients/bench/bench_options.h"

#include <CLI/CLI.hpp>

#include "server/replay/vicon/vicon_server.h"

namespace skinstream::bench {

std::optional<int> parse_bench_options(int argc, char** argv, BenchOptions& o) {
  CLI::App app{"skinstream-bench: end-to-end latency and cost of the real skinstreamd fed by a Vicon DataStream replay"};
  o.replay_tcp_congestion = server::ViconServerOptions{}.tcp_congestion;
  std::string encoding = client::to_string(o.encoding);
  bool quantised = false;
  std::string protocol = "vicon";
  app.add_option("--seconds", o.seconds, "how long to measure")->check(CLI::Range(0.5, 3600.0))->capture_default_str();
  app.add_option("--subscribers", o.subscribers, "subscribers connected in-process, one thread each")->check(CLI::Range(1, 256))->capture_default_str();
  app.add_option("--recording", o.recording, "capture the Vicon replay server streams, looped")->capture_default_str();
  app.add_option("--subject", o.subject, "subject file for the recording's performer")->required();
  app.add_option("--encoding", encoding, "what the subscribers ask for: float, quantised, compressed or parameters")
      ->check(CLI::IsMember({"float", "quantised", "compressed", "parameters"}))
      ->capture_default_str();
  app.add_flag("--quantised", quantised, "the same as --encoding quantised");
  app.add_flag("--normals", o.normals, "subscribers ask for normals too");
  app.add_flag("--decode", o.decode,
               "subscribers decode each frame (and evaluate parameters) as a renderer would; off, they read the bytes and the "
               "header only, so this machine's CPU goes to the daemon");
  app.add_flag("--paced", o.paced, "subscribers acknowledge each frame (at most 2 in flight)");
  app.add_flag("--plain-first-contact", o.plain_first_contact,
               "subscribers ask for MeshInfo and the Model plain, as clients before the Packed message did "
               "(default: packed)");
  app.add_option("--link-mbit", o.link_mbit,
                 "run the daemon in a network namespace behind a veth pair shaped by tc to this rate (Mbit/s, both ways); needs root "
                 "and iproute2")
      ->check(CLI::Range(1, 100000));
  app.add_option("--deform-threads", o.deform_threads, "skinstreamd --deform-threads")->check(CLI::Range(1, 64))->capture_default_str();
  app.add_option("--deform-cpus", o.deform_cpus, "skinstreamd --deform-cpus (default: the daemon's, auto)");
  app.add_option("--deform-spin-lead-us", o.deform_spin_lead_us, "skinstreamd --deform-spin-lead-us (default: the daemon's)")
      ->check(CLI::Range(0, 1'000'000));
  app.add_option("--publish-threads", o.publish_threads, "skinstreamd --publish-threads (default: the daemon's)")->check(CLI::Range(0, 16));
  app.add_option("--subscriber-tcp-congestion", o.subscriber_tcp_congestion,
                 "skinstreamd --subscriber-tcp-congestion (default: the daemon's, reno; \"\" = the system's)");
  app.add_option("--replay-tcp-congestion", o.replay_tcp_congestion,
                 "TCP congestion control of the replay server's connection to the daemon (\"\" = the system's)")
      ->capture_default_str();
  app.add_option("--protocol", protocol, "the capture system the replay plays to the daemon: vicon (DataStream, TCP), qtm (QTM RT, TCP) or natnet (NatNet, UDP unicast)")
      ->check(CLI::IsMember({"vicon", "qtm", "natnet"}))
      ->capture_default_str();
  app.add_option("--natnet-timestamp-jitter-us", o.natnet_timestamp_jitter_us,
                 "--protocol natnet: each frame's timestamp moved by a random offset of up to +-this many microseconds, as a "
                 "capture clock jitters")
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--natnet-clock-hz", o.natnet_clock_hz,
                 "--protocol natnet: each frame's timestamp rounded to the ticks of a clock of this frequency (e.g. 10000000)")
      ->check(CLI::Range(1.0, 1e12));
  app.add_option("--vicon-subject-name", o.vicon_subject_name, "subject (marker set) name the replay announces (default: the recording's file name)");
  app.add_option("--subjects", o.subjects, "actors on the stage: the recording streamed this many times, moved apart, as Actor1..ActorN; subscriber s follows ActorN with N = s mod subjects + 1")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  app.add_option("--subject-spacing-mm", o.subject_spacing_mm, "with --subjects: how far apart the actors stand along x")->capture_default_str();
  app.add_option("--daemon-config", o.daemon_config,
                 "skinstreamd --config FILE: daemon keys that have no flag of their own")
      ->check(CLI::ExistingFile);
  app.add_option(
         "--join-wave", o.join_wave,
         "this many more subscribers connect together --join-after-seconds into the window, while the "
         "--subscribers watch (the report's figures are the watchers'; the joiners' wait for a first "
         "frame is under join_wave)")
      ->check(CLI::Range(0, 256))
      ->capture_default_str();
  app.add_option("--join-after-seconds", o.join_after_seconds,
                 "--join-wave: when the joiners connect, in seconds into the window")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  app.add_option(
         "--joiner-nice", o.joiner_nice,
         "--join-wave: the joiners' threads at this nice level, so that their own unpacking (on a stage: "
         "other machines' CPU) does not take this machine's cores from the daemon")
      ->check(CLI::Range(0, 19))
      ->capture_default_str();
  app.add_flag(
      "--joiner-idle", o.joiner_idle,
      "--join-wave: the joiners' threads (or processes) under SCHED_IDLE: they take only the CPU nothing "
      "else wants, as other machines' would (sixty at nice 19 still weigh about one at nice 0)");
  app.add_flag("--joiner-processes", o.joiner_processes,
               "--join-wave: each joiner is a skinstream-sub process (beside this program) rather than a "
               "thread of this one; "
               "its summary is reported under join_wave.processes");
  app.add_option("--joiner-multicast", o.joiner_multicast,
                 "--join-wave: the joiners take every frame's parameters from the daemon's multicast group "
                 "GROUP:PORT over the shaped link, MeshInfo and the Model from its offer (needs --link-mbit "
                 "and --encoding parameters)");
  app.add_option(
         "--multicast-offer-mbit", o.multicast_offer_mbit,
         "--joiner-multicast: the daemon offers MeshInfo and the Model to the group at this rate (Mbit/s); "
         "0: none, the joiners fetch them over TCP")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  app.add_option(
         "--record-ab", o.record_ab_seconds,
         "recording A/B in one run: the daemon records a take for this many seconds, then none for as long, "
         "in turn (through its control API); the report's record_ab splits the figures by recording on and "
         "off")
      ->check(CLI::Range(0.0, 3600.0));
  app.add_flag("--json", o.json, "print the report as JSON");
  app.add_flag("--hostile-waves", o.hostile_waves,
               "the soak: hostile peers (stalled, flooding, churning) connect and leave in waves while the subscribers measure "
               "(loopback only)");
  app.add_option("--wave-seconds", o.wave_seconds, "--hostile-waves: how long each wave stays")->check(CLI::Range(1, 3600))->capture_default_str();
  app.add_option("--calm-seconds", o.calm_seconds, "--hostile-waves: the calm after each wave, at whose end RSS is noted")
      ->check(CLI::Range(1, 3600))
      ->capture_default_str();
  // How many of each hostile peer a wave opens (0: none of that kind).
  HostilePeers& peers = o.hostile_peers;
  const struct {
    const char* flag;
    int* count;
    const char* what;
  } hostile_counts[] = {
      {"--stallers", &peers.stallers, "TCP subscribers that say Hello and never read, all connecting at once"},
      {"--websocket-stallers", &peers.websocket_stallers, "WebSocket subscribers that never read"},
      {"--garbage-flooders", &peers.garbage_flooders, "connections sending bytes that are no protocol"},
      {"--hello-flooders", &peers.hello_flooders, "subscribers sending Hello after Hello"},
      {"--churn-per-second", &peers.churn_per_second, "connections a second that say Hello and hang up"}};
  for (const auto& kind : hostile_counts)
    app.add_option(kind.flag, *kind.count, std::string("--hostile-waves, per wave: ") + kind.what)
        ->check(CLI::Range(0, 4096))
        ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  o.encoding = client::encoding_from_string(quantised ? "quantised" : encoding);
  o.protocol = protocol == "qtm" ? CaptureProtocol::Qtm : protocol == "natnet" ? CaptureProtocol::NatNet : CaptureProtocol::Vicon;
  return std::nullopt;
}

}  // namespace skinstream::bench
