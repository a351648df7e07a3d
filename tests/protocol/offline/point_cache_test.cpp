#include "protocol/offline/point_cache.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>

#include "protocol/files/file_error.h"
#include "support/allocation_counter.h"
#include "support/file_error_assertion.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

using test::read_bytes;
using test::write_bytes;

std::vector<Vec3> sample(int points, int k) {
  std::vector<Vec3> v;
  for (int i = 0; i < points; ++i) v.emplace_back(i + 0.25 * k, -1000.5 * k, 0.125 * i * k);
  return v;
}

TEST(PointCache, RejectsBadArgumentsAndMisuse) {
  const std::string path = test::scratch_path("bad.pc2");
  EXPECT_TRUE(test::throws_file_error([&] { PointCacheWriter(path, 0); }, path, "at least one point"));
  EXPECT_TRUE(test::throws_file_error([&] { PointCacheWriter(path, 3, 0.0f, 0.0f); }, path, "sample rate"));
  const std::string unwritable = test::scratch_path("no_dir/x.pc2");
  EXPECT_TRUE(test::throws_file_error([&] { PointCacheWriter(unwritable, 3); }, unwritable, "cannot create"));
  PointCacheWriter writer(path, 3);
  const std::vector<Vec3> two = sample(2, 1);
  EXPECT_TRUE(test::throws_file_error([&] { writer.append(two); }, path, "sample of 2 points, the cache has 3"));
  writer.close();
  const std::vector<Vec3> three = sample(3, 1);
  EXPECT_TRUE(test::throws_file_error([&] { writer.append(three); }, path, "append after close"));
}

TEST(PointCache, HeaderBytesAreExactlyTheFormat) {
  const std::string path = test::scratch_path("header.pc2");
  {
    PointCacheWriter writer(path, 2, 10.0f, 1.0f);
    writer.append(sample(2, 1));
    writer.append(sample(2, 2));
    writer.append(sample(2, 3));
    EXPECT_EQ(writer.sample_count(), 3);
  }  // the destructor closes and fixes the count
  const std::string bytes = read_bytes(path);
  ASSERT_EQ(bytes.size(), 32u + 3 * 2 * 12);
  const unsigned char expected[32] = {
      'P', 'O', 'I', 'N', 'T', 'C', 'A', 'C', 'H', 'E', '2', 0,  // signature with its trailing NUL
      1,   0,   0,   0,                                          // int32 version 1
      2,   0,   0,   0,                                          // int32 points
      0,   0,   0x20, 0x41,                                      // float32 start frame 10.0
      0,   0,   0x80, 0x3f,                                      // float32 sample rate 1.0
      3,   0,   0,   0};                                         // int32 samples
  EXPECT_EQ(std::memcmp(bytes.data(), expected, 32), 0);
  // First sample, first point: float32 x y z = 0.25, -1000.5, 0.
  float xyz[3];
  std::memcpy(xyz, bytes.data() + 32, 12);
  EXPECT_EQ(xyz[0], 0.25f);
  EXPECT_EQ(xyz[1], -1000.5f);
  EXPECT_EQ(xyz[2], 0.0f);
}

TEST(PointCache, RoundTripsManySamplesWithoutAllocatingPerSample) {
  const std::string path = test::scratch_path("round_trip.pc2");
  const int points = 1000, samples = 25;
  std::vector<std::vector<Vec3>> frames;
  for (int k = 0; k < samples; ++k) frames.push_back(sample(points, k));
  PointCacheWriter writer(path, points, -3.0f, 0.5f);
  {
    test::CountAllocations counter;
    for (const auto& f : frames) writer.append(f);
    EXPECT_EQ(counter.count(), 0u);
  }
  writer.close();
  writer.close();  // a second close does nothing

  const PointCache cache = read_point_cache(path);
  EXPECT_EQ(cache.point_count, points);
  EXPECT_EQ(cache.sample_count, samples);
  EXPECT_EQ(cache.start_frame, -3.0f);
  EXPECT_EQ(cache.sample_rate, 0.5f);
  for (int k = 0; k < samples; ++k)
    for (int i = 0; i < points; ++i) ASSERT_EQ(cache.at(k, i), frames[k][i].cast<float>().cast<double>());
}

TEST(PointCache, EmptyCacheIsValid) {
  const std::string path = test::scratch_path("empty.pc2");
  PointCacheWriter(path, 5).close();
  const PointCache cache = read_point_cache(path);
  EXPECT_EQ(cache.point_count, 5);
  EXPECT_EQ(cache.sample_count, 0);
  EXPECT_TRUE(cache.positions.empty());
}

TEST(PointCache, RejectsDamagedFiles) {
  const std::string good_path = test::scratch_path("good.pc2");
  {
    PointCacheWriter writer(good_path, 4);
    writer.append(sample(4, 1));
    writer.append(sample(4, 2));
  }
  const std::string good = read_bytes(good_path);
  const std::string path = test::scratch_path("damaged.pc2");
  EXPECT_TRUE(test::throws_file_error([&] { read_point_cache(test::scratch_path("none.pc2")); },
                                      test::scratch_path("none.pc2"), "cannot open"));
  for (size_t cut : {size_t{0}, size_t{11}, size_t{31}, size_t{32}, good.size() - 1}) {
    write_bytes(path, good.substr(0, cut));
    EXPECT_TRUE(test::throws_file_error([&] { read_point_cache(path); }, path, "truncated")) << cut;
  }
  write_bytes(path, good + "x");
  EXPECT_TRUE(test::throws_file_error([&] { read_point_cache(path); }, path, "1 bytes after the last sample"));
  std::string bad = good;
  bad[10] = '3';
  write_bytes(path, bad);
  EXPECT_TRUE(test::throws_file_error([&] { read_point_cache(path); }, path, "no POINTCACHE2 signature"));
  bad = good;
  bad[12] = 2;
  write_bytes(path, bad);
  EXPECT_TRUE(test::throws_file_error([&] { read_point_cache(path); }, path, "PC2 version 2"));
  bad = good;
  bad[31] = static_cast<char>(0x80);  // sample count negative
  write_bytes(path, bad);
  EXPECT_TRUE(test::throws_file_error([&] { read_point_cache(path); }, path, "negative"));
  bad = good;
  bad[29] = 1;  // 258 samples claimed
  write_bytes(path, bad);
  EXPECT_TRUE(test::throws_file_error([&] { read_point_cache(path); }, path, "truncated: header says 258 samples"));
}

}  // namespace
}  // namespace skinstream
