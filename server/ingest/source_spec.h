#pragma once
// The one source the daemon reads frames from, as one value. The configuration has a key per
// kind (replay, vicon, vicon_multicast, qtm, natnet) and at most one may be set: source_spec_of
// is where that is read and checked, make_source where the source is made from it.

#include <memory>
#include <string>

#include "server/asio.h"
#include "server/config.h"
#include "server/ingest/frame_source.h"

namespace skinstream::server {

struct SourceSpec {
  enum class Kind { None, Replay, Vicon, ViconMulticast, Qtm, NatNet };
  Kind kind = Kind::None;
  std::string where;  // the capture file (Replay), else the address as the configuration gives it
  bool operator==(const SourceSpec&) const = default;
};

// The configuration's source; ConfigError when it names more than one.
SourceSpec source_spec_of(const DaemonConfig& config);

// The source `spec` names, with what else it needs from `config` (replay speed, limits, timeouts),
// sending its frames to `sink`; nullptr for Kind::None. Throws ConfigError for an address that
// is not of its kind's form, and what the source's constructor throws (a replay file that cannot
// be read).
std::unique_ptr<FrameSource> make_source(asio::io_context& io, const SourceSpec& spec,
                                         const DaemonConfig& config, SourceSink& sink);

}  // namespace skinstream::server
