#include "protocol/offline/point_cache.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "protocol/byte_reader.h"
#include "protocol/files/file_error.h"
#include "protocol/files/whole_file.h"
#include "protocol/span_writer.h"

namespace skinstream {

namespace {

static_assert(std::endian::native == std::endian::little, "PC2 is little-endian; so must the host be");

// Byte offset of the sample count in the header.
constexpr long kSampleCountOffset = 28;

}  // namespace

PointCacheWriter::PointCacheWriter(const std::string& path, int point_count, float start_frame, float sample_rate)
    : path_(path), point_count_(point_count) {
  if (point_count <= 0) throw FileError(path, "a point cache needs at least one point, got " + std::to_string(point_count));
  if (!std::isfinite(start_frame) || !std::isfinite(sample_rate) || sample_rate <= 0.0f)
    throw FileError(path, "bad start frame or sample rate");
  buffer_.resize(static_cast<size_t>(point_count) * 3);
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) throw FileError(path, "cannot create");
  unsigned char header[kPointCacheHeaderBytes];
  SpanWriter out(header);
  std::memcpy(out.reserve(sizeof kPointCacheSignature), kPointCacheSignature, sizeof kPointCacheSignature);
  out.put<int32_t>(1);
  out.put<int32_t>(point_count);
  out.put<float>(start_frame);
  out.put<float>(sample_rate);
  out.put<int32_t>(0);
  if (std::fwrite(header, 1, sizeof header, file_) != sizeof header) {
    std::fclose(file_);
    file_ = nullptr;
    throw FileError(path, "write failed");
  }
}

PointCacheWriter::~PointCacheWriter() {
  try {
    if (file_) close();
  } catch (const FileError&) {
    // A destructor cannot report; callers who care call close().
  }
}

void PointCacheWriter::append(std::span<const Vec3> points) {
  if (!file_) throw FileError(path_, "append after close");
  if (points.size() != static_cast<size_t>(point_count_))
    throw FileError(path_, "sample of " + std::to_string(points.size()) + " points, the cache has " +
                               std::to_string(point_count_));
  float* out = buffer_.data();
  for (const Vec3& p : points) {
    *out++ = static_cast<float>(p.x());
    *out++ = static_cast<float>(p.y());
    *out++ = static_cast<float>(p.z());
  }
  if (std::fwrite(buffer_.data(), sizeof(float), buffer_.size(), file_) != buffer_.size())
    throw FileError(path_, "write failed at sample " + std::to_string(sample_count_));
  ++sample_count_;
}

void PointCacheWriter::close() {
  if (!file_) return;
  const int32_t count = sample_count_;
  const bool ok = std::fseek(file_, kSampleCountOffset, SEEK_SET) == 0 && std::fwrite(&count, 4, 1, file_) == 1;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!ok || !closed) throw FileError(path_, "could not finish the header");
}

PointCache read_point_cache(const std::string& path) {
  const std::string bytes = read_whole_file(path);
  if (bytes.size() < kPointCacheHeaderBytes)
    throw FileError(path, "truncated: " + std::to_string(bytes.size()) + " bytes, a PC2 header has 32");
  if (std::memcmp(bytes.data(), kPointCacheSignature, sizeof kPointCacheSignature) != 0)
    throw FileError(path, "not a PC2 point cache (no POINTCACHE2 signature)");
  // Sizes checked before each read: none can fail.
  ByteReader r(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size());
  r.skip(sizeof kPointCacheSignature, "signature");
  const int32_t version = r.get<int32_t>("version");
  if (version != 1) throw FileError(path, "PC2 version " + std::to_string(version) + ", only 1 is read");
  PointCache cache;
  cache.point_count = r.get<int32_t>("point count");
  cache.start_frame = r.get<float>("start frame");
  cache.sample_rate = r.get<float>("sample rate");
  cache.sample_count = r.get<int32_t>("sample count");
  if (cache.point_count < 0 || cache.sample_count < 0)
    throw FileError(path, "negative point or sample count in the header");
  if (!std::isfinite(cache.start_frame) || !std::isfinite(cache.sample_rate))
    throw FileError(path, "non-finite start frame or sample rate");
  const uint64_t values = static_cast<uint64_t>(cache.point_count) * static_cast<uint64_t>(cache.sample_count) * 3;
  const uint64_t expected = kPointCacheHeaderBytes + values * 4;
  if (bytes.size() < expected)
    throw FileError(path, "truncated: header says " + std::to_string(cache.sample_count) + " samples of " +
                              std::to_string(cache.point_count) + " points (" + std::to_string(expected) +
                              " bytes), file has " + std::to_string(bytes.size()));
  if (bytes.size() > expected)
    throw FileError(path, std::to_string(bytes.size() - expected) + " bytes after the last sample");
  cache.positions.resize(static_cast<size_t>(values / 3));
  for (Vec3& v : cache.positions) {
    const float x = r.get<float>("samples"), y = r.get<float>("samples"), z = r.get<float>("samples");
    v = Vec3(x, y, z);
  }
  return cache;
}

}  // namespace skinstream
