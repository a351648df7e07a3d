#include "server/ingest/source_spec.h"

#include <spdlog/spdlog.h>

#include <chrono>

#include "protocol/natnet/natnet.h"
#include "protocol/qtm/qtm_rt.h"
#include "server/ingest/file_replay_source.h"
#include "server/ingest/natnet_source.h"
#include "server/ingest/qtm_source.h"
#include "server/ingest/vicon_multicast_source.h"
#include "server/ingest/vicon_source.h"

namespace skinstream::server {
namespace {

// A "HOST:PORT" source, for a config that may not have been through validate().
HostPort source_host_port(const std::string& flag, const std::string& text) {
  const std::optional<HostPort> parsed = parse_host_port(text);
  if (!parsed) throw ConfigError(flag + " " + text + ": expected HOST:PORT with a port of 1-65535");
  return *parsed;
}

// A "HOST[:PORT]" source (qtm, natnet), likewise.
HostPort source_host_port(const std::string& flag, const std::string& text, uint16_t default_port) {
  const std::optional<HostPort> parsed = parse_host_with_port(text, default_port);
  if (!parsed) throw ConfigError(flag + " " + text + ": expected HOST or HOST:PORT with a port of 1-65535");
  return *parsed;
}

vicon::DescriptionLimits source_description_limits(const DaemonConfig& config) {
  vicon::DescriptionLimits limits;
  limits.max_subjects = static_cast<uint32_t>(config.source_max_subjects);
  limits.max_markers_per_subject = static_cast<uint32_t>(config.source_max_markers_per_subject);
  limits.max_name_bytes = static_cast<uint32_t>(config.source_max_name_bytes);
  return limits;
}

}  // namespace

SourceSpec source_spec_of(const DaemonConfig& config) {
  const std::pair<SourceSpec::Kind, const std::string*> keys[] = {
      {SourceSpec::Kind::Replay, &config.replay},
      {SourceSpec::Kind::Vicon, &config.vicon},
      {SourceSpec::Kind::ViconMulticast, &config.vicon_multicast},
      {SourceSpec::Kind::Qtm, &config.qtm},
      {SourceSpec::Kind::NatNet, &config.natnet}};
  SourceSpec spec;
  for (const auto& [kind, where] : keys) {
    if (where->empty()) continue;
    if (spec.kind != SourceSpec::Kind::None)
      throw ConfigError(
          "configuration: give one source: a replay file, a Vicon server, a Vicon multicast address, a QTM "
          "or a "
          "NatNet server");
    spec = {kind, *where};
  }
  return spec;
}

std::unique_ptr<FrameSource> make_source(asio::io_context& io, const SourceSpec& spec,
                                         const DaemonConfig& config, SourceSink& sink) {
  const auto handshake_timeout = std::chrono::milliseconds(config.source_handshake_timeout_ms);
  const auto stall_timeout = std::chrono::milliseconds(config.source_stall_ms);
  switch (spec.kind) {
    case SourceSpec::Kind::None:
      return nullptr;
    case SourceSpec::Kind::Replay:
      return std::make_unique<FileReplaySource>(
          io, spec.where, sink, ReplayOptions{config.loop, config.speed, config.replay_subject});
    case SourceSpec::Kind::Vicon: {
      const HostPort address = source_host_port("--vicon", spec.where);
      ViconSourceOptions options;
      options.host = address.host;
      options.port = address.port;
      options.mode =
          config.vicon_pull ? ViconSourceOptions::Mode::ClientPull : ViconSourceOptions::Mode::ServerPush;
      options.limits = source_description_limits(config);
      options.handshake_timeout = handshake_timeout;
      options.stall_timeout = stall_timeout;
      spdlog::info("source: Vicon DataStream {}:{} ({})", options.host, options.port,
                   config.vicon_pull ? "client pull" : "server push");
      return std::make_unique<ViconSource>(io, std::move(options), sink);
    }
    case SourceSpec::Kind::ViconMulticast: {
      const HostPort address = source_host_port("--vicon-multicast", spec.where);
      ViconMulticastSourceOptions options;
      options.group = address.host;
      options.port = address.port;
      options.limits = source_description_limits(config);
      spdlog::info("source: Vicon DataStream multicast {}:{} (receive only)", options.group, options.port);
      return std::make_unique<ViconMulticastSource>(io, std::move(options), sink);
    }
    case SourceSpec::Kind::Qtm: {
      const HostPort address = source_host_port("--qtm", spec.where, qtm::kLittleEndianPort);
      QtmSourceOptions options;
      options.host = address.host;
      options.port = address.port;
      options.handshake_timeout = handshake_timeout;
      options.stall_timeout = stall_timeout;
      spdlog::info("source: QTM RT {}:{}", options.host, options.port);
      return std::make_unique<QtmSource>(io, std::move(options), sink);
    }
    case SourceSpec::Kind::NatNet: {
      const HostPort address = source_host_port("--natnet", spec.where, natnet::kCommandPort);
      NatNetSourceOptions options;
      options.host = address.host;
      options.command_port = address.port;
      options.interface_address = config.natnet_interface;
      options.bind_address = config.bind_address;
      options.reply_timeout = handshake_timeout;
      options.stall_timeout = stall_timeout;
      spdlog::info("source: NatNet {}:{}", options.host, options.command_port);
      return std::make_unique<NatNetSource>(io, std::move(options), sink);
    }
  }
  return nullptr;
}

}  // namespace skinstream::server
