// Writes a capture as a C3D file: header block, a parameter section with the POINT, ANALOG and
// TRIAL groups, then the point data, in the byte order and float format of the chosen processor.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "protocol/files/c3d.h"
#include "protocol/files/c3d_format.h"
#include "protocol/files/c3d_preamble.h"
#include "protocol/files/capture_checks.h"
#include "protocol/files/file_error.h"

namespace skinstream {
namespace {

using c3d_format::kBlockBytes;
using c3d_format::kHeaderKey;
constexpr uint8_t kParameterBlock = 2;  // the parameter section follows the header directly
constexpr size_t kMaxParameterBlocks = 255;
constexpr int kMaxArrayDimension = 255;  // dimensions are stored as bytes
// Readers treat the link between parameter records as a signed 16-bit offset.
constexpr size_t kMaxRecordBytes = 32000;
constexpr int kIntegerRange = 32000;  // integer storage keeps below int16 max, leaving headroom

enum ParameterType : int8_t { kChar = -1, kInt16 = 2, kFloat = 4 };

// Encodes 16-bit words and 32-bit floats for one processor.
class WordEncoder {
 public:
  WordEncoder(const std::string& path, C3dProcessor processor) : path_(path), processor_(processor) {}

  void u16(uint8_t* out, uint16_t value) const {
    if (processor_ == C3dProcessor::Mips) {
      out[0] = static_cast<uint8_t>(value >> 8);
      out[1] = static_cast<uint8_t>(value);
    } else {
      out[0] = static_cast<uint8_t>(value);
      out[1] = static_cast<uint8_t>(value >> 8);
    }
  }
  void i16(uint8_t* out, int16_t value) const { u16(out, static_cast<uint16_t>(value)); }

  void f32(uint8_t* out, float value) const {
    if (!std::isfinite(value))
      throw FileError(path_, "cannot store non-finite value " + std::to_string(value));
    const uint32_t bits = processor_ == C3dProcessor::Dec ? vax_bits(value) : ieee_bits(value);
    // Intel stores the low word first. MIPS is big-endian throughout; VAX F keeps the word
    // holding sign and exponent first, each word little-endian: both put the high word first.
    const bool high_first = processor_ != C3dProcessor::Intel;
    u16(out, static_cast<uint16_t>(high_first ? bits >> 16 : bits));
    u16(out + 2, static_cast<uint16_t>(high_first ? bits : bits >> 16));
  }

 private:
  static uint32_t ieee_bits(float value) {
    uint32_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    return bits;
  }

  // VAX F: value = 0.1fff (binary) x 2^(exponent - 128), fraction without the leading 1.
  uint32_t vax_bits(float value) const {
    if (value == 0.0f) return 0;
    int power;
    const double mantissa = std::frexp(std::abs(static_cast<double>(value)), &power);  // [0.5, 1)
    const int exponent = power + 128;
    if (exponent <= 0) return 0;  // below the smallest VAX float: flush to zero
    if (exponent > 255)
      throw FileError(path_, "value " + std::to_string(value) + " too large for DEC floats");
    const auto fraction = static_cast<uint32_t>(std::ldexp(mantissa * 2.0 - 1.0, 23));
    return (value < 0 ? 0x80000000u : 0u) | (static_cast<uint32_t>(exponent) << 23) | fraction;
  }

  const std::string& path_;
  C3dProcessor processor_;
};

int processor_byte(C3dProcessor processor) {
  switch (processor) {
    case C3dProcessor::Intel:
      return 84;
    case C3dProcessor::Dec:
      return 85;
    case C3dProcessor::Mips:
      return 86;
  }
  return 84;
}

// Builds the parameter records. Each record: name length, group id (negative for a group),
// name, link to the next record, then type/dimensions/data (parameters) and a description.
class ParameterSectionWriter {
 public:
  explicit ParameterSectionWriter(const WordEncoder& encode) : encode_(encode) {}

  void group(int8_t id, const std::string& name, const std::string& description) {
    std::vector<uint8_t> body;
    append_description(body, description);
    record(static_cast<int8_t>(-id), name, body);
  }

  void int16s(int8_t group, const std::string& name, const std::vector<int>& dims,
              const std::vector<uint16_t>& values) {
    std::vector<uint8_t> data(values.size() * 2);
    for (size_t i = 0; i < values.size(); ++i) encode_.u16(&data[2 * i], values[i]);
    parameter(group, name, kInt16, dims, data);
  }
  void int16(int8_t group, const std::string& name, uint16_t value) { int16s(group, name, {}, {value}); }

  void float32(int8_t group, const std::string& name, float value) {
    std::vector<uint8_t> data(4);
    encode_.f32(data.data(), value);
    parameter(group, name, kFloat, {}, data);
  }

  // Fixed-width strings padded with spaces: dimensions {width, count}.
  void strings(int8_t group, const std::string& name, const std::vector<std::string>& values, int width) {
    std::vector<uint8_t> data(values.size() * width, ' ');
    for (size_t i = 0; i < values.size(); ++i)
      std::copy(values[i].begin(), values[i].end(), data.begin() + i * width);
    parameter(group, name, kChar, {width, static_cast<int>(values.size())}, data);
  }
  void string(int8_t group, const std::string& name, const std::string& value) {
    parameter(group, name, kChar, {static_cast<int>(value.size())},
              std::vector<uint8_t>(value.begin(), value.end()));
  }

  // The section with its 4-byte preamble, padded to whole blocks; the last link is 0.
  std::vector<uint8_t> finish(C3dProcessor processor) {
    std::vector<uint8_t> out{1, kHeaderKey, 0, static_cast<uint8_t>(processor_byte(processor))};
    if (last_link_ != kNone) encode_.u16(&records_[last_link_], 0);
    out.insert(out.end(), records_.begin(), records_.end());
    out.resize((out.size() + kBlockBytes - 1) / kBlockBytes * kBlockBytes, 0);
    out[2] = static_cast<uint8_t>(std::min(out.size() / kBlockBytes, size_t{255}));
    return out;
  }

 private:
  static constexpr size_t kNone = static_cast<size_t>(-1);

  static void append_description(std::vector<uint8_t>& body, const std::string& description) {
    body.push_back(static_cast<uint8_t>(description.size()));
    body.insert(body.end(), description.begin(), description.end());
  }

  void parameter(int8_t group, const std::string& name, ParameterType type, const std::vector<int>& dims,
                 const std::vector<uint8_t>& data) {
    std::vector<uint8_t> body{static_cast<uint8_t>(type), static_cast<uint8_t>(dims.size())};
    for (int d : dims) body.push_back(static_cast<uint8_t>(d));
    body.insert(body.end(), data.begin(), data.end());
    append_description(body, "");
    record(group, name, body);
  }

  void record(int8_t id, const std::string& name, const std::vector<uint8_t>& body) {
    records_.push_back(static_cast<uint8_t>(name.size()));
    records_.push_back(static_cast<uint8_t>(id));
    records_.insert(records_.end(), name.begin(), name.end());
    last_link_ = records_.size();
    records_.resize(records_.size() + 2);
    encode_.u16(&records_[last_link_], static_cast<uint16_t>(2 + body.size()));
    records_.insert(records_.end(), body.begin(), body.end());
  }

  const WordEncoder& encode_;
  std::vector<uint8_t> records_;
  size_t last_link_ = kNone;
};

struct FrameRange {
  uint64_t first = 1;
  uint64_t count = 0;
  uint64_t last() const { return first + std::max<uint64_t>(count, 1) - 1; }
};

std::vector<uint8_t> parameter_section(const C3dPointLayout& layout, const WordEncoder& encode,
                                       const C3dWriteOptions& options, float scale, uint16_t data_start) {
  enum : int8_t { kPoint = 1, kAnalog = 2, kTrial = 3 };
  const std::vector<std::string>& labels = layout.labels;
  const FrameRange frames{static_cast<uint64_t>(layout.first_frame), layout.frame_count};
  ParameterSectionWriter p(encode);
  p.group(kPoint, "POINT", "3-D point parameters");
  p.int16(kPoint, "USED", static_cast<uint16_t>(labels.size()));
  // 16 bits read unsigned by readers; longer captures are described by the TRIAL fields.
  p.int16(kPoint, "FRAMES", static_cast<uint16_t>(std::min<uint64_t>(frames.count, 65535)));
  p.int16(kPoint, "DATA_START", data_start);
  p.float32(kPoint, "SCALE", scale);
  p.float32(kPoint, "RATE", static_cast<float>(layout.rate_hz));
  p.string(kPoint, "UNITS", "mm");

  int width = 1;
  for (const std::string& label : labels) width = std::max(width, static_cast<int>(label.size()));
  // Dimensions are bytes: more than 255 labels continue in LABELS2, LABELS3...
  const size_t per_array = std::min<size_t>(kMaxArrayDimension, kMaxRecordBytes / width);
  const std::vector<std::string> no_descriptions(labels.size(), "");
  for (size_t first = 0, part = 1; first < labels.size() || part == 1; first += per_array, ++part) {
    const size_t end = std::min(labels.size(), first + per_array);
    const std::string suffix = part == 1 ? "" : std::to_string(part);
    p.strings(kPoint, "LABELS" + suffix, {labels.begin() + first, labels.begin() + end}, width);
    p.strings(kPoint, "DESCRIPTIONS" + suffix,
              {no_descriptions.begin() + first, no_descriptions.begin() + end}, 1);
  }

  p.group(kAnalog, "ANALOG", "Analog data parameters");
  p.int16(kAnalog, "USED", 0);
  p.float32(kAnalog, "RATE", 0.0f);

  // 32-bit frame numbers as (low word, high word).
  const auto field = [](uint64_t frame) {
    return std::vector<uint16_t>{static_cast<uint16_t>(frame & 0xFFFF), static_cast<uint16_t>(frame >> 16)};
  };
  p.group(kTrial, "TRIAL", "Trial parameters");
  p.int16s(kTrial, "ACTUAL_START_FIELD", {2}, field(frames.first));
  p.int16s(kTrial, "ACTUAL_END_FIELD", {2}, field(frames.last()));
  p.float32(kTrial, "CAMERA_RATE", static_cast<float>(layout.rate_hz));
  return p.finish(options.processor);
}

std::vector<uint8_t> header_block(const C3dPointLayout& layout, const WordEncoder& encode, float scale,
                                  uint16_t data_start) {
  std::vector<uint8_t> header(kBlockBytes, 0);
  header[0] = kParameterBlock;
  header[1] = kHeaderKey;
  const auto clip16 = [](uint64_t value) { return static_cast<uint16_t>(std::min<uint64_t>(value, 65535)); };
  const FrameRange frames{static_cast<uint64_t>(layout.first_frame), layout.frame_count};
  encode.u16(&header[2], static_cast<uint16_t>(layout.labels.size()));
  encode.u16(&header[4], 0);  // analog words per frame
  encode.u16(&header[6], clip16(frames.first));
  encode.u16(&header[8], clip16(frames.last()));
  encode.u16(&header[10], 0);  // maximum interpolation gap
  encode.f32(&header[12], scale);
  encode.u16(&header[16], data_start);
  encode.u16(&header[18], 0);  // analog samples per frame
  encode.f32(&header[20], static_cast<float>(layout.rate_hz));
  return header;
}

// Integer storage: the largest coordinate maps to kIntegerRange, so every value fits an int16.
float integer_scale(const Capture& capture) {
  double largest = 0.0;
  for (const Vec3& p : capture.positions)
    if (is_present(p)) largest = std::max(largest, p.cwiseAbs().maxCoeff());
  const float scale = static_cast<float>(largest / kIntegerRange);
  return std::isnormal(scale) ? scale : 1.0f;
}

void encode_sample(uint8_t* out, const Vec3& p, float scale, const WordEncoder& encode,
                   const C3dWriteOptions& options) {
  if (options.float_storage) {
    const bool present = is_present(p);
    for (int axis = 0; axis < 3; ++axis)
      encode.f32(out + 4 * axis, present ? static_cast<float>(p[axis]) : 0.0f);
    encode.f32(out + 12, present ? 0.0f : -1.0f);  // residual: negative marks a missing sample
    return;
  }
  if (!is_present(p)) {
    for (int word = 0; word < 3; ++word) encode.i16(out + 2 * word, 0);
    encode.i16(out + 6, -1);
    return;
  }
  long q[3];
  int largest_axis = 0;
  for (int axis = 0; axis < 3; ++axis) {
    q[axis] = std::clamp(std::lround(p[axis] / scale), -32767L, 32767L);
    if (std::abs(p[axis]) > std::abs(p[largest_axis])) largest_axis = axis;
  }
  // (0,0,0) reads back as missing; keep the sample present at the cost of one scale step.
  if (q[0] == 0 && q[1] == 0 && q[2] == 0) q[largest_axis] = p[largest_axis] < 0 ? -1 : 1;
  for (int axis = 0; axis < 3; ++axis) encode.i16(out + 2 * axis, static_cast<int16_t>(q[axis]));
  encode.i16(out + 6, 0);
}

void check_c3d_layout(const C3dPointLayout& layout, const std::string& path) {
  if (layout.labels.size() > 65535)
    throw FileError(path,
                    "C3D holds at most 65535 points, capture has " + std::to_string(layout.labels.size()));
  if (layout.first_frame < 0)
    throw FileError(path, "C3D cannot store negative first frame " + std::to_string(layout.first_frame));
  for (const std::string& label : layout.labels)
    if (label.size() > kMaxArrayDimension)
      throw FileError(path, "label longer than 255 characters: " + label.substr(0, 40) + "...");
}

}  // namespace

std::vector<uint8_t> c3d_preamble(const C3dPointLayout& layout, const std::string& path,
                                  const C3dWriteOptions& options, float scale) {
  check_c3d_layout(layout, path);
  const WordEncoder encode(path, options.processor);
  // The section's size does not depend on DATA_START's value: build once to learn it.
  const size_t parameter_blocks = parameter_section(layout, encode, options, scale, 0).size() / kBlockBytes;
  if (parameter_blocks > kMaxParameterBlocks)
    throw FileError(path,
                    "labels need " + std::to_string(parameter_blocks) + " parameter blocks, C3D allows 255");
  const auto data_start = static_cast<uint16_t>(kParameterBlock + parameter_blocks);
  std::vector<uint8_t> bytes = header_block(layout, encode, scale, data_start);
  const std::vector<uint8_t> parameters = parameter_section(layout, encode, options, scale, data_start);
  bytes.insert(bytes.end(), parameters.begin(), parameters.end());
  return bytes;
}

void write_c3d(const Capture& capture, const std::string& path, const C3dWriteOptions& options) {
  check_capture_shape(capture, path);
  // A negative scale selects float storage; -1 leaves residuals unscaled.
  const float scale = options.float_storage ? -1.0f : integer_scale(capture);
  const C3dPointLayout layout{capture.labels, capture.rate_hz, capture.first_frame,
                              static_cast<uint64_t>(std::max(capture.frame_count, 0))};
  const std::vector<uint8_t> preamble = c3d_preamble(layout, path, options, scale);
  const WordEncoder encode(path, options.processor);

  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw FileError(path, "cannot open for writing");
  const auto put = [&](const std::vector<uint8_t>& bytes) {
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  };
  put(preamble);

  const size_t sample_bytes = options.float_storage ? 16 : 8;
  const size_t frame_bytes = sample_bytes * capture.labels.size();
  const size_t frames_per_chunk = frame_bytes ? std::max<size_t>(1, (4u << 20) / frame_bytes) : 1;
  std::vector<uint8_t> chunk;
  uint64_t data_bytes = 0;
  for (int first = 0; first < capture.frame_count && frame_bytes;
       first += static_cast<int>(frames_per_chunk)) {
    const int count = static_cast<int>(std::min<size_t>(frames_per_chunk, capture.frame_count - first));
    chunk.resize(count * frame_bytes);
    for (int f = 0; f < count; ++f)
      for (int p = 0; p < capture.point_count(); ++p)
        encode_sample(&chunk[f * frame_bytes + p * sample_bytes], capture.at(first + f, p), scale, encode,
                      options);
    put(chunk);
    data_bytes += chunk.size();
  }
  put(std::vector<uint8_t>((kBlockBytes - data_bytes % kBlockBytes) % kBlockBytes, 0));  // whole blocks
  out.close();
  if (!out) throw FileError(path, "write failed");
}

}  // namespace skinstream
