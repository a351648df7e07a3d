#include "protocol/research/png_file.h"

#include <zlib.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "protocol/files/file_error.h"
#include "protocol/files/whole_file.h"

namespace skinstream {

namespace {

constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
// Refuses headers that would need more than 1 GiB of pixels (a corrupt size, not a real image).
constexpr uint64_t kMaxDecodedBytes = uint64_t{1} << 30;

void put_u32(std::string& out, uint32_t v) {
  const char bytes[4] = {static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8),
                         static_cast<char>(v)};
  out.append(bytes, 4);
}

uint32_t get_u32(const unsigned char* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | uint32_t{p[3]};
}

// length, type, data, CRC-32 of type and data.
void put_chunk(std::string& out, const char type[4], const std::string& data) {
  put_u32(out, static_cast<uint32_t>(data.size()));
  const size_t start = out.size();
  out.append(type, 4);
  out += data;
  const uLong crc = crc32(0L, reinterpret_cast<const Bytef*>(out.data() + start), static_cast<uInt>(out.size() - start));
  put_u32(out, static_cast<uint32_t>(crc));
}

int paeth(int a, int b, int c) {
  const int p = a + b - c;
  const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) return a;
  return pb <= pc ? b : c;
}

}  // namespace

void write_png(const std::string& path, const render::Image& image) {
  if (image.width <= 0 || image.height <= 0) throw FileError(path, "cannot write an empty image");
  const size_t row_bytes = 3 * static_cast<size_t>(image.width);
  if (image.rgb.size() != row_bytes * static_cast<size_t>(image.height))
    throw FileError(path, "image holds " + std::to_string(image.rgb.size()) + " bytes, not 3 x " +
                              std::to_string(image.width) + " x " + std::to_string(image.height));
  // Each scanline starts with its filter type; 0 (none) keeps the writer trivially correct.
  std::string raw;
  raw.reserve((row_bytes + 1) * static_cast<size_t>(image.height));
  for (int y = 0; y < image.height; ++y) {
    raw += '\0';
    raw.append(reinterpret_cast<const char*>(image.rgb.data()) + row_bytes * static_cast<size_t>(y), row_bytes);
  }
  uLongf compressed_size = compressBound(static_cast<uLong>(raw.size()));
  std::string compressed(compressed_size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(compressed.data()), &compressed_size,
                reinterpret_cast<const Bytef*>(raw.data()), static_cast<uLong>(raw.size()), 6) != Z_OK)
    throw FileError(path, "zlib compression failed");
  compressed.resize(compressed_size);

  std::string header;
  put_u32(header, static_cast<uint32_t>(image.width));
  put_u32(header, static_cast<uint32_t>(image.height));
  header += std::string("\x08\x02\x00\x00\x00", 5);  // 8 bits, truecolour, deflate, adaptive filters, no interlace

  std::string file(reinterpret_cast<const char*>(kSignature), sizeof kSignature);
  put_chunk(file, "IHDR", header);
  put_chunk(file, "IDAT", compressed);
  put_chunk(file, "IEND", "");
  std::ofstream out(path, std::ios::binary);
  if (!out) throw FileError(path, "cannot create");
  out.write(file.data(), static_cast<std::streamsize>(file.size()));
  if (!out) throw FileError(path, "write failed");
}

render::Image read_png(const std::string& path) {
  const std::string file = read_whole_file(path);
  const auto* bytes = reinterpret_cast<const unsigned char*>(file.data());
  if (file.size() < sizeof kSignature || std::memcmp(bytes, kSignature, sizeof kSignature) != 0)
    throw FileError(path, "not a PNG file (bad signature)");

  uint32_t width = 0, height = 0;
  int channels = 0;
  bool have_header = false, have_end = false;
  std::string idat;
  size_t pos = sizeof kSignature;
  while (!have_end) {
    if (file.size() - pos < 12) throw FileError(path, "truncated: file ends inside a chunk");
    const uint32_t length = get_u32(bytes + pos);
    const std::string type(file, pos + 4, 4);
    if (length > file.size() - pos - 12) throw FileError(path, "truncated: chunk " + type + " runs past the end");
    const unsigned char* data = bytes + pos + 8;
    const uint32_t stored_crc = get_u32(data + length);
    if (static_cast<uint32_t>(crc32(0L, bytes + pos + 4, length + 4)) != stored_crc)
      throw FileError(path, "corrupt: CRC mismatch in chunk " + type);
    pos += 12 + static_cast<size_t>(length);
    if (!have_header && type != "IHDR") throw FileError(path, "corrupt: first chunk is not IHDR");
    if (type == "IHDR") {
      if (have_header || length != 13) throw FileError(path, "corrupt: bad IHDR");
      width = get_u32(data);
      height = get_u32(data + 4);
      const int depth = data[8], colour_type = data[9];
      if (width == 0 || height == 0 || width > 0x7fffffffu || height > 0x7fffffffu)
        throw FileError(path, "corrupt: image size " + std::to_string(width) + " x " + std::to_string(height));
      if (depth != 8) throw FileError(path, "unsupported PNG: bit depth " + std::to_string(depth) + " (only 8 is read)");
      if (colour_type == 0) channels = 1;
      else if (colour_type == 2) channels = 3;
      else if (colour_type == 6) channels = 4;
      else throw FileError(path, "unsupported PNG: colour type " + std::to_string(colour_type));
      if (data[10] != 0 || data[11] != 0) throw FileError(path, "corrupt: unknown compression or filter method");
      if (data[12] != 0) throw FileError(path, "unsupported PNG: interlaced");
      if (uint64_t{width} * height * static_cast<uint64_t>(channels + 1) > kMaxDecodedBytes)
        throw FileError(path, "unsupported PNG: " + std::to_string(width) + " x " + std::to_string(height) + " is too large");
      have_header = true;
    } else if (type == "IDAT") {
      idat.append(reinterpret_cast<const char*>(data), length);
    } else if (type == "IEND") {
      have_end = true;
    } else if (type[0] >= 'A' && type[0] <= 'Z') {
      throw FileError(path, "unsupported PNG: critical chunk " + type);
    }  // other ancillary chunks (gAMA, tEXt, ...) are skipped
  }
  if (pos != file.size()) throw FileError(path, "corrupt: " + std::to_string(file.size() - pos) + " bytes after IEND");
  if (idat.empty()) throw FileError(path, "corrupt: no image data");

  const size_t row_bytes = static_cast<size_t>(width) * static_cast<size_t>(channels);
  const size_t expected = (row_bytes + 1) * height;
  std::string raw(expected, '\0');
  uLongf produced = static_cast<uLongf>(expected);
  const int z = uncompress(reinterpret_cast<Bytef*>(raw.data()), &produced,
                           reinterpret_cast<const Bytef*>(idat.data()), static_cast<uLong>(idat.size()));
  if (z != Z_OK || produced != expected)
    throw FileError(path, "corrupt: image data does not inflate to " + std::to_string(height) + " rows of " +
                              std::to_string(width) + " pixels");

  // Undo the scanline filters in place (bpp = channels for 8-bit samples).
  auto* rows = reinterpret_cast<unsigned char*>(raw.data());
  for (uint32_t y = 0; y < height; ++y) {
    unsigned char* line = rows + y * (row_bytes + 1);
    const unsigned char* previous = y > 0 ? line - (row_bytes + 1) : nullptr;
    const int filter = line[0];
    unsigned char* px = line + 1;
    const unsigned char* up = previous ? previous + 1 : nullptr;
    for (size_t i = 0; i < row_bytes; ++i) {
      const int a = i >= static_cast<size_t>(channels) ? px[i - static_cast<size_t>(channels)] : 0;
      const int b = up ? up[i] : 0;
      const int c = up && i >= static_cast<size_t>(channels) ? up[i - static_cast<size_t>(channels)] : 0;
      switch (filter) {
        case 0: break;
        case 1: px[i] = static_cast<unsigned char>(px[i] + a); break;
        case 2: px[i] = static_cast<unsigned char>(px[i] + b); break;
        case 3: px[i] = static_cast<unsigned char>(px[i] + (a + b) / 2); break;
        case 4: px[i] = static_cast<unsigned char>(px[i] + paeth(a, b, c)); break;
        default: throw FileError(path, "corrupt: unknown filter " + std::to_string(filter) + " on row " + std::to_string(y));
      }
    }
  }

  render::Image image(static_cast<int>(width), static_cast<int>(height), {});
  for (uint32_t y = 0; y < height; ++y) {
    const unsigned char* px = rows + y * (row_bytes + 1) + 1;
    for (uint32_t x = 0; x < width; ++x, px += channels) {
      const unsigned char r = px[0];
      image.set(static_cast<int>(x), static_cast<int>(y),
                channels == 1 ? render::Rgb{r, r, r} : render::Rgb{r, px[1], px[2]});
    }
  }
  return image;
}

}  // namespace skinstream
