#pragma once
// Who else sees each frame the pipeline publishes, as filled markers rather than encoded
// messages: the take recorder. Called on the pipeline thread for every frame it sends: must
// not block, allocate or take long (copying into preallocated storage is the budget).

#include <cstdint>
#include <span>

#include "core/capture.h"
#include "core/marker_status.h"
#include "server/ingest/source_frame.h"

namespace skinstream::server {

struct FilledFrameView {
  uint32_t frame_number = 0;
  int64_t source_time_ns = 0;
  int64_t receive_time_ns = 0;
  std::span<const Vec3> positions;       // one per subject marker, in its order
  std::span<const MarkerStatus> status;  // how each was obtained
};

class FilledFrameObserver {
 public:
  virtual ~FilledFrameObserver() = default;
  virtual void on_filled(const FilledFrameView& frame) = 0;
};

}  // namespace skinstream::server
