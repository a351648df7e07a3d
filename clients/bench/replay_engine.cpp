#include "clients/bench/replay_engine.h"

#include "server/replay/natnet/natnet_server.h"
#include "server/replay/qtm/qtm_server.h"
#include "server/replay/vicon/vicon_server.h"

namespace skinstream::bench {

const char* to_string(CaptureProtocol protocol) {
  switch (protocol) {
    case CaptureProtocol::Vicon: return "vicon";
    case CaptureProtocol::Qtm: return "qtm";
    case CaptureProtocol::NatNet: return "natnet";
  }
  return "?";
}

struct ReplayEngine::Servers {
  std::unique_ptr<server::ViconServer> vicon;
  std::unique_ptr<server::QtmServer> qtm;
  std::unique_ptr<server::NatNetServer> natnet;
};

ReplayEngine::ReplayEngine(server::asio::io_context& io, const std::vector<ReplaySubject>& subjects, const ReplayEngineOptions& options)
    : options_(options), servers_(std::make_unique<Servers>()) {
  switch (options.protocol) {
    case CaptureProtocol::Vicon: {
      server::ViconServerOptions o;
      o.bind_address = options.bind_address;
      o.port = 0;
      o.loop = true;
      o.tcp_congestion = options.tcp_congestion;
      servers_->vicon = std::make_unique<server::ViconServer>(io, subjects, o);
      break;
    }
    case CaptureProtocol::Qtm: {
      server::QtmServerOptions o;
      o.bind_address = options.bind_address;
      o.port = 0;
      o.loop = true;
      servers_->qtm = std::make_unique<server::QtmServer>(io, subjects, o);
      break;
    }
    case CaptureProtocol::NatNet: {
      server::NatNetServerOptions o;
      o.bind_address = options.bind_address;
      o.command_port = 0;
      o.multicast = false;  // unicast to the daemon: multicast does not loop back on every machine
      o.loop = true;
      o.timestamp_jitter_us = options.natnet_timestamp_jitter_us;
      o.timestamp_clock_hz = options.natnet_clock_hz;
      servers_->natnet = std::make_unique<server::NatNetServer>(io, subjects, o);
      break;
    }
  }
}

ReplayEngine::~ReplayEngine() = default;

void ReplayEngine::set_frame_hook(FrameHook hook) {
  if (servers_->vicon) servers_->vicon->set_frame_hook(std::move(hook));
  else if (servers_->qtm) servers_->qtm->set_frame_hook(std::move(hook));
  else servers_->natnet->set_frame_hook(std::move(hook));
}

void ReplayEngine::start() {
  if (servers_->vicon) servers_->vicon->start();
  else if (servers_->qtm) servers_->qtm->start();
  else servers_->natnet->start();
}

std::string ReplayEngine::daemon_source_option() const {
  const std::string& a = options_.bind_address;
  if (servers_->vicon) return "--vicon " + a + ":" + std::to_string(servers_->vicon->port());
  if (servers_->qtm) return "--qtm " + a + ":" + std::to_string(servers_->qtm->port());
  return "--natnet " + a + ":" + std::to_string(servers_->natnet->command_port());
}

uint64_t ReplayEngine::frames_sent() const {
  if (servers_->vicon) return servers_->vicon->stats().frame_packets_sent.load();
  if (servers_->qtm) return servers_->qtm->stats().frame_packets_sent.load();
  return servers_->natnet->stats().frames_produced.load() - servers_->natnet->stats().frames_too_large.load();
}

uint64_t ReplayEngine::frames_dropped() const {
  if (servers_->vicon) return servers_->vicon->stats().frames_dropped.load();
  if (servers_->qtm) return servers_->qtm->stats().frames_dropped.load();
  return servers_->natnet->stats().frames_too_large.load();
}

}  // namespace skinstream::bench
