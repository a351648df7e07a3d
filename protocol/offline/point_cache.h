#pragma once
// The PC2 point cache (3ds Max PointCache2, read by Blender's mesh cache modifier and Maya):
// a vertex animation for a mesh whose topology is stored elsewhere (an OBJ with the same vertex
// order). Layout, little-endian, 32-byte header:
//   char[12] "POINTCACHE2\0" | int32 version = 1 | int32 point count | float32 start frame |
//   float32 sample rate (frames between samples, 1 = every frame) | int32 sample count |
// then per sample, per point, float32 x y z.
#include <cstdint>
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include "core/capture.h"

namespace skinstream {

inline constexpr char kPointCacheSignature[12] = {'P', 'O', 'I', 'N', 'T', 'C', 'A', 'C', 'H', 'E', '2', '\0'};
inline constexpr int kPointCacheHeaderBytes = 32;

// Streams samples to a PC2 file as they are produced: the header is written at open with a
// sample count of 0 and fixed at close() (until then read_point_cache refuses the file as
// padded). append() allocates nothing: its float buffer is sized at open.
// Not copyable; moving is not needed by any caller so far.
class PointCacheWriter {
 public:
  // Throws FileError when the file cannot be created or point_count is not positive.
  PointCacheWriter(const std::string& path, int point_count, float start_frame = 0.0f, float sample_rate = 1.0f);
  ~PointCacheWriter();  // closes if close() was not called; errors are then lost
  PointCacheWriter(const PointCacheWriter&) = delete;
  PointCacheWriter& operator=(const PointCacheWriter&) = delete;

  // One sample: exactly point_count positions. Throws FileError on a count mismatch, a write
  // failure or a call after close().
  void append(std::span<const Vec3> points);
  // Writes the sample count into the header and closes the file. Throws FileError.
  void close();

  int point_count() const { return point_count_; }
  int sample_count() const { return sample_count_; }

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  int point_count_ = 0;
  int sample_count_ = 0;
  std::vector<float> buffer_;
};

// A whole cache in memory (tests, tools). positions is sample-major.
struct PointCache {
  int point_count = 0;
  float start_frame = 0.0f;
  float sample_rate = 1.0f;
  int sample_count = 0;
  std::vector<Vec3> positions;  // positions[sample * point_count + point]

  const Vec3& at(int sample, int point) const {
    return positions[static_cast<size_t>(sample) * static_cast<size_t>(point_count) + static_cast<size_t>(point)];
  }
};

// Throws FileError for a missing file, a wrong signature or version, a negative count, or a
// size that does not match the header (truncated or padded).
PointCache read_point_cache(const std::string& path);

}  // namespace skinstream
