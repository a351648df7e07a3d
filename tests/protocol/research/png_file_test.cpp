#include "protocol/research/png_file.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdlib>
#include <cstring>
#include <random>

#include "protocol/files/file_error.h"
#include "protocol/meshes/mesh_file.h"
#include "protocol/offline/makehuman.h"
#include "support/file_error_assertion.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

using test::read_bytes;
using test::write_bytes;

using render::Image;
using render::Rgb;

Image random_image(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  Image im(w, h, {});
  for (auto& b : im.rgb) b = static_cast<std::uint8_t>(rng() & 0xff);
  return im;
}

TEST(PngFile, RejectsEmptyImagesAndUnwritablePaths) {
  const std::string path = test::scratch_path("empty.png");
  EXPECT_TRUE(test::throws_file_error([&] { write_png(path, Image()); }, path, "empty image"));
  Image bad(4, 4, {});
  bad.rgb.pop_back();
  EXPECT_TRUE(test::throws_file_error([&] { write_png(path, bad); }, path, "not 3 x 4 x 4"));
  const std::string unwritable = test::scratch_path("no_dir/x.png");
  EXPECT_TRUE(test::throws_file_error([&] { write_png(unwritable, Image(2, 2, {})); }, unwritable, "cannot create"));
}

TEST(PngFile, WritesSignatureAndHeaderAsTheSpecificationSays) {
  const std::string path = test::scratch_path("header.png");
  write_png(path, Image(300, 2, {1, 2, 3}));
  const std::string bytes = read_bytes(path);
  const unsigned char expected[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n',  // signature
                                    0, 0, 0, 13, 'I', 'H', 'D', 'R',            // IHDR, 13 bytes
                                    0, 0, 1, 44, 0, 0, 0, 2,                    // 300 x 2, big-endian
                                    8, 2, 0, 0, 0};                             // 8-bit RGB, no interlace
  ASSERT_GT(bytes.size(), sizeof expected + 12);
  EXPECT_EQ(std::memcmp(bytes.data(), expected, sizeof expected), 0);
  EXPECT_EQ(bytes.substr(bytes.size() - 12), std::string("\0\0\0\0IEND\xae\x42\x60\x82", 12));
}

TEST(PngFile, RoundTripsExactly) {
  for (auto [w, h] : {std::pair{1, 1}, std::pair{37, 23}, std::pair{640, 480}}) {
    const Image im = random_image(w, h, static_cast<unsigned>(w * h));
    const std::string path = test::scratch_path("round_trip.png");
    write_png(path, im);
    const Image back = read_png(path);
    EXPECT_EQ(back.width, w);
    EXPECT_EQ(back.height, h);
    EXPECT_EQ(back.rgb, im.rgb);
  }
}

// A PNG written here with every scanline filter type, RGBA, to check the reader's unfiltering.
std::string chunk(const std::string& type, const std::string& data) {
  std::string out;
  for (int s = 24; s >= 0; s -= 8) out += static_cast<char>((data.size() >> s) & 0xff);
  const std::string body = type + data;
  out += body;
  const uLong crc = crc32(0L, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size()));
  for (int s = 24; s >= 0; s -= 8) out += static_cast<char>((crc >> s) & 0xff);
  return out;
}

TEST(PngFile, ReadsEveryFilterTypeAndDropsAlpha) {
  const int w = 9, h = 10, bpp = 4;
  std::mt19937 rng(7);
  std::vector<std::vector<int>> rows(h, std::vector<int>(w * bpp));
  for (auto& r : rows)
    for (int& v : r) v = static_cast<int>(rng() & 0xff);
  std::string raw;
  for (int y = 0; y < h; ++y) {
    const int filter = y % 5;
    raw += static_cast<char>(filter);
    for (int i = 0; i < w * bpp; ++i) {
      const int a = i >= bpp ? rows[y][i - bpp] : 0;
      const int b = y > 0 ? rows[y - 1][i] : 0;
      const int c = y > 0 && i >= bpp ? rows[y - 1][i - bpp] : 0;
      const int p = a + b - c;
      const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
      const int predictor[5] = {0, a, b, (a + b) / 2, (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c)};
      raw += static_cast<char>((rows[y][i] - predictor[filter]) & 0xff);
    }
  }
  uLongf size = compressBound(static_cast<uLong>(raw.size()));
  std::string z(size, '\0');
  ASSERT_EQ(compress(reinterpret_cast<Bytef*>(z.data()), &size, reinterpret_cast<const Bytef*>(raw.data()),
                     static_cast<uLong>(raw.size())),
            Z_OK);
  z.resize(size);
  const std::string ihdr = std::string("\0\0\0\x09\0\0\0\x0a\x08\x06\0\0\0", 13);
  // The image data split over two IDAT chunks, with an ancillary chunk before them.
  const std::string file = std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) + chunk("tEXt", "a\0b") +
                           chunk("IDAT", z.substr(0, 5)) + chunk("IDAT", z.substr(5)) + chunk("IEND", "");
  const std::string path = test::scratch_path("filters.png");
  write_bytes(path, file);
  const Image im = read_png(path);
  ASSERT_EQ(im.width, w);
  ASSERT_EQ(im.height, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const Rgb c = im.at(x, y);
      ASSERT_EQ(c.r, rows[y][x * 4]);
      ASSERT_EQ(c.g, rows[y][x * 4 + 1]);
      ASSERT_EQ(c.b, rows[y][x * 4 + 2]);
    }
}

TEST(PngFile, RejectsDamagedFiles) {
  const std::string good_path = test::scratch_path("good.png");
  write_png(good_path, random_image(20, 20, 3));
  const std::string good = read_bytes(good_path);
  const std::string path = test::scratch_path("damaged.png");
  EXPECT_TRUE(test::throws_file_error([&] { read_png(test::scratch_path("none.png")); }, test::scratch_path("none.png"),
                                      "cannot open"));
  write_bytes(path, "GIF89a");
  EXPECT_TRUE(test::throws_file_error([&] { read_png(path); }, path, "not a PNG file"));
  for (size_t cut : {size_t{8}, size_t{20}, size_t{40}, good.size() - 1}) {
    write_bytes(path, good.substr(0, cut));
    EXPECT_TRUE(test::throws_file_error([&] { read_png(path); }, path, "truncated")) << cut;
  }
  std::string bad = good;
  bad[50] = static_cast<char>(bad[50] ^ 0x10);  // inside the IDAT data
  write_bytes(path, bad);
  EXPECT_TRUE(test::throws_file_error([&] { read_png(path); }, path, "CRC mismatch in chunk IDAT"));
  write_bytes(path, good + "junk");
  EXPECT_TRUE(test::throws_file_error([&] { read_png(path); }, path, "4 bytes after IEND"));
  // Random damage: refused cleanly or, if the CRCs happen to survive, decoded.
  std::mt19937 rng(11);
  for (int round = 0; round < 200; ++round) {
    bad = good;
    bad[std::uniform_int_distribution<size_t>(0, bad.size() - 1)(rng)] = static_cast<char>(rng() & 0xff);
    if (round % 2) bad.resize(std::uniform_int_distribution<size_t>(0, bad.size())(rng));
    write_bytes(path, bad);
    try {
      read_png(path);
    } catch (const FileError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u);
    }
  }
}

// The real body seen from the front, through the whole chain: mesh file, renderer, PNG.
TEST(PngFile, MakeHumanFrontViewLooksLikeAStandingPerson) {
  TriangleMesh body = read_mesh(test::shared_path("data/meshes/makehuman/makehuman_hm08_body_only.obj"));
  for (Vec3& p : body.vertices) p = makehuman_to_skinstream(p);  // mm, Z up, facing +Y
  const render::RenderMesh mesh{body.vertices, body.faces};
  const render::Camera camera = render::frame_view(body.vertices, render::View::front, 480, 640);
  const Image im = render::render_mesh(mesh, camera);
  const std::string path = test::scratch_path("makehuman_front.png");
  write_png(path, im);
  const Image back = read_png(path);
  ASSERT_EQ(back.rgb, im.rgb);

  // The silhouette: tall and narrow, centred, filling most of the frame's height.
  int left = im.width, right = -1, top = im.height, bottom = -1;
  long covered = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x)
      if (!(im.at(x, y) == Rgb{255, 255, 255})) {
        left = std::min(left, x);
        right = std::max(right, x);
        top = std::min(top, y);
        bottom = std::max(bottom, y);
        ++covered;
      }
  const int tall = bottom - top + 1, wide = right - left + 1;
  EXPECT_GT(tall, 0.8 * im.height);
  EXPECT_GT(tall, 1.5 * wide);
  EXPECT_NEAR(0.5 * (left + right), 0.5 * im.width, 0.05 * im.width);
  EXPECT_LT(covered, tall * wide / 2);  // a body with arms apart, not a block
  // The head is at the top: the top row of the silhouette is narrow and centred.
  int head_left = im.width, head_right = -1;
  for (int x = 0; x < im.width; ++x)
    if (!(im.at(x, top + tall / 20) == Rgb{255, 255, 255})) {
      head_left = std::min(head_left, x);
      head_right = std::max(head_right, x);
    }
  EXPECT_LT(head_right - head_left, wide / 4);
}

}  // namespace
}  // namespace skinstream
