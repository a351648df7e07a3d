#pragma once
// A C3D file written while a take goes on, readable by any C3D reader up to its last commit()
// whatever happens to the writer (kill -9, a full disk): frames are appended after the
// parameter section, and only once they are on disk (fdatasync) does the preamble say how many
// there are (rewritten in place, then fsync). A crash leaves a valid file of the committed
// frames, possibly followed by frames no reader looks at; recover_c3d_take() counts those in.
//
// Float storage in the Intel format only (what every reader reads); missing samples have the
// residual -1 and zero coordinates, as write_c3d writes them.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/capture.h"

namespace skinstream {

class C3dTakeWriter {
 public:
  // Creates `path` (refuses one that exists) and writes the preamble of an empty take.
  // Throws FileError naming the path.
  C3dTakeWriter(std::string path, std::vector<std::string> labels, double rate_hz);
  ~C3dTakeWriter();  // closes without committing what was appended since the last commit
  C3dTakeWriter(const C3dTakeWriter&) = delete;
  C3dTakeWriter& operator=(const C3dTakeWriter&) = delete;

  int point_count() const { return static_cast<int>(labels_.size()); }
  // Queues one frame of point_count() points (NaN: missing). No I/O; allocates only when more
  // frames are queued between two commits than ever before.
  void append(std::span<const Vec3> points);
  // Writes the queued frames, syncs them, then rewrites the preamble with the new count and
  // syncs that. Throws FileError (with the system's reason: "No space left on device") when the
  // disk refuses; the file then still reads as the frames of the last commit that succeeded.
  void commit();
  // Commits and pads the file to whole blocks, as write_c3d leaves it.
  void close();

  uint64_t frames_committed() const { return committed_; }
  uint64_t frames_queued() const { return queued_; }
  const std::string& path() const { return path_; }

 private:
  void write_all(const uint8_t* data, size_t size, uint64_t offset, const char* what);
  void write_preamble(uint64_t frames);

  std::string path_;
  std::vector<std::string> labels_;
  double rate_hz_ = 0.0;
  int fd_ = -1;
  uint64_t data_offset_ = 0;  // where frame 0 starts
  size_t preamble_bytes_ = 0;
  uint64_t committed_ = 0, queued_ = 0;
  std::vector<uint8_t> pending_;
};

// Closes a take file its writer never closed: counts the whole frames after the parameter
// section (committed or not: the process died, the page cache kept them), says that many in the
// preamble, drops a partial last frame and pads to whole blocks. Returns the frame count.
// `labels` and `rate_hz` are what the writer was made with (the take's sidecar keeps them);
// throws FileError when the file's start does not match them.
uint64_t recover_c3d_take(const std::string& path, const std::vector<std::string>& labels, double rate_hz);

}  // namespace skinstream
