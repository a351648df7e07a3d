#pragma once
// The recordings skinstream-replay streams together: each read (C3D or TRC) and named as a
// subject after its file stem (or the name given for a single recording); names made unique by a
// suffix ("_2"). Several recordings must share a frame rate unless one is given.

#include <memory>
#include <string>
#include <vector>

#include "core/capture.h"
#include "protocol/replay_subject.h"

namespace skinstream::server {

struct ReplayRecordings {
  std::vector<std::unique_ptr<Capture>> captures;  // stable addresses for the subjects
  std::vector<ReplaySubject> subjects;
  double rate_hz = 0.0;  // the stream's: `rate` if given, else the recordings' own
};

// Throws FileError for a file that cannot be read or holds no frames, std::invalid_argument for
// recordings of different rates (without `rate`) or a missing rate.
ReplayRecordings load_replay_recordings(const std::vector<std::string>& paths, const std::string& subject_name,
                                        double rate);

}  // namespace skinstream::server
