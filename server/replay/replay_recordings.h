#pragma once
// The recordings skinstream-replay streams together: each read (C3D or TRC) and named as a
// subject, by the names given (one per recording) or else after its file stem, stems made unique
// by a suffix ("_2"). Several recordings must share a frame rate unless one is given.

#include <memory>
#include <string>
#include <vector>

#include "core/capture.h"
#include "protocol/files/replay_subject.h"

namespace skinstream::server {

struct ReplayRecordings {
  std::vector<std::unique_ptr<Capture>> captures;  // stable addresses for the subjects
  std::vector<ReplaySubject> subjects;
  double rate_hz = 0.0;  // the stream's: `rate` if given, else the recordings' own
};

// Throws FileError for a file that cannot be read or holds no frames, std::invalid_argument for
// recordings of different rates (without `rate`), a missing rate, or names that are not one per
// recording or name one subject twice.
ReplayRecordings load_replay_recordings(const std::vector<std::string>& paths, const std::vector<std::string>& subject_names,
                                        double rate);

}  // namespace skinstream::server
