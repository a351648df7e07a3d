// Reads the 3D points of a C3D file. The layout, from the c3d.org specification:
//   block 1      header: parameter block number, point count, analog words per frame, first and
//                last frame, scale, data start block, analog samples per frame, frame rate
//   block p..    parameter section: 4-byte preamble (byte 3 = processor type) then group and
//                parameter records, each pointing to the next
//   block d..    data: per frame, per point x y z and a residual word, then the analog samples
// Every offset read from the file is checked against the bytes actually present, so a damaged
// or hostile file can only end in a FileError.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "protocol/files/c3d.h"
#include "protocol/files/c3d_format.h"
#include "protocol/files/file_error.h"

namespace skinstream {
namespace {

using c3d_format::kBlockBytes;
using c3d_format::kHeaderKey;
constexpr int kProcessorByteBase = 83;  // processor byte = 83 + {1 Intel, 2 DEC, 3 MIPS}
// The parameter pointer and block count are single bytes, so the header and parameter section
// always lie within the first 509 blocks.
constexpr uint64_t kMaxPrefixBytes = (254 + 255) * kBlockBytes;

// Header words (16-bit), as byte offsets into block 1.
constexpr size_t kHeaderPointCount = 2;
constexpr size_t kHeaderAnalogWordsPerFrame = 4;
constexpr size_t kHeaderFirstFrame = 6;
constexpr size_t kHeaderLastFrame = 8;
constexpr size_t kHeaderScale = 12;
constexpr size_t kHeaderDataStart = 16;
constexpr size_t kHeaderAnalogSamplesPerFrame = 18;
constexpr size_t kHeaderFrameRate = 20;

// VAX F-float: sign, 8-bit exponent (bias 128), 23-bit fraction with a hidden leading 0.1,
// stored as two little-endian 16-bit words, the high word (sign and exponent) first.
float decode_vax_float(const uint8_t* b) {
  const uint32_t high = b[0] | (b[1] << 8);
  const uint32_t low = b[2] | (b[3] << 8);
  const uint32_t bits = (high << 16) | low;
  const bool negative = bits >> 31;
  const int exponent = static_cast<int>((bits >> 23) & 0xFF);
  const uint32_t fraction = bits & 0x7FFFFF;
  if (exponent == 0) return negative ? std::numeric_limits<float>::quiet_NaN() : 0.0f;  // reserved / zero
  const double magnitude = std::ldexp(1.0 + fraction / 8388608.0, exponent - 129);
  return static_cast<float>(negative ? -magnitude : magnitude);
}

// Decodes 16-bit words and 32-bit floats in the byte order and float format of one processor.
struct WordFormat {
  C3dProcessor processor = C3dProcessor::Intel;

  uint16_t u16(const uint8_t* b) const {
    return processor == C3dProcessor::Mips ? static_cast<uint16_t>((b[0] << 8) | b[1])
                                           : static_cast<uint16_t>(b[0] | (b[1] << 8));
  }
  int16_t i16(const uint8_t* b) const { return static_cast<int16_t>(u16(b)); }
  float f32(const uint8_t* b) const {
    if (processor == C3dProcessor::Dec) return decode_vax_float(b);
    uint32_t bits;
    if (processor == C3dProcessor::Mips)
      bits = (uint32_t{b[0]} << 24) | (uint32_t{b[1]} << 16) | (uint32_t{b[2]} << 8) | b[3];
    else
      bits = (uint32_t{b[3]} << 24) | (uint32_t{b[2]} << 16) | (uint32_t{b[1]} << 8) | b[0];
    float value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }
};

// Numbers in messages: shortest form ("-50", not "-50.000000").
std::string text_of(double value) {
  char text[32];
  return std::string(text, std::to_chars(text, text + sizeof text, value).ptr);
}

// Rates are decimal numbers stored as floats (59.94 becomes 59.94000244...): take the shortest
// decimal that reads back to the same float, so 59.94 comes back as the double 59.94.
double decimal_of(float value) {
  char text[32];
  const char* end = std::to_chars(text, text + sizeof text, value).ptr;
  double decimal = value;
  std::from_chars(text, end, decimal);
  return decimal;
}

std::string upper(std::string text) {
  for (char& c : text) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return text;
}

// Labels and units are padded with spaces (or NULs, by some writers) to the array width.
std::string trim_padding(const std::string& text) {
  const auto is_pad = [](char c) { return c == ' ' || c == '\0' || c == '\t'; };
  size_t begin = 0, end = text.size();
  while (begin < end && is_pad(text[begin])) ++begin;
  while (end > begin && is_pad(text[end - 1])) --end;
  return text.substr(begin, end - begin);
}

// The header block and the parameter section, held in memory, with checked access.
class FilePrefix {
 public:
  FilePrefix(const std::string& path, std::vector<uint8_t> bytes) : path_(path), bytes_(std::move(bytes)) {}

  // Pointer to `count` bytes at `offset`, or a FileError saying what was being read.
  const uint8_t* at(uint64_t offset, uint64_t count, const std::string& what) const {
    if (offset > bytes_.size() || count > bytes_.size() - offset)
      throw FileError(path_,
                      "corrupt: " + what + " at byte " + std::to_string(offset) + " runs past the end");
    return bytes_.data() + offset;
  }

 private:
  const std::string& path_;
  std::vector<uint8_t> bytes_;
};

// One parameter record: its type, dimensions and where its data lies in the prefix.
struct Parameter {
  int type = 0;  // -1 char, 1 byte, 2 int16, 4 float
  std::vector<int> dims;
  uint64_t data_offset = 0;
  uint64_t element_count = 1;
};

class ParameterSection {
 public:
  ParameterSection(const std::string& path, const FilePrefix& prefix, WordFormat format)
      : path_(path), prefix_(prefix), format_(format) {}

  // Walks the records in [begin, end). Records are chained by a forward offset; a zero name
  // length, a zero group id or a zero offset ends the section.
  void parse(uint64_t begin, uint64_t end) {
    std::map<int, std::string> group_names;
    std::vector<std::pair<int, std::pair<std::string, Parameter>>> parameters;
    uint64_t at = begin;
    while (at + 2 <= end) {
      const uint8_t* head = prefix_.at(at, 2, "parameter record");
      const int name_length = std::abs(static_cast<int8_t>(head[0]));
      const int group_id = static_cast<int8_t>(head[1]);
      if (name_length == 0 || group_id == 0) break;
      const uint64_t name_at = at + 2;
      const uint64_t link_at = name_at + name_length;
      if (link_at + 2 > end) throw corrupt("parameter record at byte " + std::to_string(at), end);
      const std::string name = upper(std::string(
          reinterpret_cast<const char*>(prefix_.at(name_at, name_length, "parameter name")), name_length));
      const uint16_t link = format_.u16(prefix_.at(link_at, 2, "parameter link"));
      if (group_id < 0) {
        group_names.emplace(-group_id, name);
      } else {
        parameters.push_back({group_id, {name, read_parameter(name, link_at + 2, end)}});
      }
      if (link == 0) break;
      at = link_at + link;
    }
    for (auto& [group_id, entry] : parameters) {
      const auto group = group_names.find(group_id);
      if (group == group_names.end()) continue;  // a parameter of an undeclared group: unusable
      by_name_.emplace(group->second + ":" + entry.first, std::move(entry.second));
    }
  }

  const Parameter* find(const std::string& key) const {
    const auto it = by_name_.find(key);
    return it == by_name_.end() ? nullptr : &it->second;
  }

  // Element `index` of a numeric parameter as a number; int16 read signed.
  std::optional<double> number(const std::string& key, uint64_t index = 0) const {
    const Parameter* p = find(key);
    if (!p || p->type == -1 || index >= p->element_count) return std::nullopt;
    const uint8_t* b = prefix_.at(p->data_offset + index * std::abs(p->type), std::abs(p->type), key);
    switch (p->type) {
      case 1:
        return b[0];
      case 2:
        return format_.i16(b);
      default:
        return format_.f32(b);
    }
  }

  // A count stored in an int16 parameter. Writers store counts above 32767 (frames, points)
  // as the same 16 bits read unsigned, so negative int16 values are read as unsigned.
  std::optional<uint64_t> count(const std::string& key, uint64_t index = 0) const {
    const Parameter* p = find(key);
    if (!p || p->type == -1 || index >= p->element_count) return std::nullopt;
    const uint8_t* b = prefix_.at(p->data_offset + index * std::abs(p->type), std::abs(p->type), key);
    if (p->type == 1) return b[0];
    if (p->type == 2) return format_.u16(b);
    const float value = format_.f32(b);
    if (!(value >= 0.0f) || value > 4.0e9f || value != std::floor(value))
      throw FileError(path_, "corrupt: " + key + " is " + text_of(value) + ", not a count");
    return static_cast<uint64_t>(value);
  }

  // The strings of a character parameter: the first dimension is the string width, the rest
  // multiply to the string count.
  std::optional<std::vector<std::string>> strings(const std::string& key) const {
    const Parameter* p = find(key);
    if (!p) return std::nullopt;
    if (p->type != -1) throw FileError(path_, "corrupt: " + key + " is not a character parameter");
    std::vector<std::string> out;
    if (p->dims.empty()) return out;
    const uint64_t width = p->dims[0];
    if (width == 0) return out;
    const uint64_t count = p->element_count / width;
    const char* text = reinterpret_cast<const char*>(prefix_.at(p->data_offset, p->element_count, key));
    for (uint64_t i = 0; i < count; ++i) out.push_back(trim_padding(std::string(text + i * width, width)));
    return out;
  }

 private:
  FileError corrupt(const std::string& what, uint64_t end) const {
    return FileError(path_, "corrupt: " + what + " runs past the parameter section (ends at byte " +
                                std::to_string(end) + ")");
  }

  // Parameter body: type, dimension count, dimensions, data (then a description we skip).
  Parameter read_parameter(const std::string& name, uint64_t at, uint64_t end) const {
    const std::string where = "parameter " + quoted_text(name);
    if (at + 2 > end) throw corrupt(where, end);
    const uint8_t* b = prefix_.at(at, 2, where);
    Parameter p;
    p.type = static_cast<int8_t>(b[0]);
    if (p.type != -1 && p.type != 1 && p.type != 2 && p.type != 4)
      throw FileError(path_, "corrupt: " + where + " has data type " + std::to_string(p.type) +
                                 " (expected -1, 1, 2 or 4)");
    const int dim_count = b[1];
    if (at + 2 + dim_count > end) throw corrupt(where, end);
    const uint8_t* dims = prefix_.at(at + 2, dim_count, where);
    p.data_offset = at + 2 + dim_count;
    const uint64_t room = end - p.data_offset;
    for (int i = 0; i < dim_count; ++i) {
      p.dims.push_back(dims[i]);
      p.element_count *= dims[i];
      if (p.element_count * std::abs(p.type) > room)
        throw corrupt(where, end);  // checked per step: no overflow
    }
    if (p.element_count * std::abs(p.type) > room) throw corrupt(where, end);  // a scalar (no dimensions)
    return p;
  }

  const std::string& path_;
  const FilePrefix& prefix_;
  WordFormat format_;
  std::map<std::string, Parameter> by_name_;
};

double unit_to_millimetres(const std::string& path, const std::string& units) {
  const std::string u = upper(units);
  if (u.empty() || u == "MM") return 1.0;  // the C3D default
  if (u == "CM") return 10.0;
  if (u == "DM") return 100.0;
  if (u == "M") return 1000.0;
  throw FileError(path, "unknown POINT:UNITS " + quoted_text(units) + " (expected mm, cm, dm or m)");
}

// Everything needed to decode the data section, gathered from header and parameters.
struct Layout {
  WordFormat format;
  uint64_t points = 0;
  uint64_t frames = 0;
  int64_t first_frame = 1;
  double rate = 0.0;
  float scale = 1.0f;
  bool float_storage = false;
  float to_millimetres = 1.0f;
  uint64_t analog_words_per_frame = 0;
  uint64_t data_offset = 0;
  std::vector<std::string> labels;

  uint64_t word_bytes() const { return float_storage ? 4 : 2; }
  uint64_t frame_bytes() const { return (4 * points + analog_words_per_frame) * word_bytes(); }
};

std::vector<std::string> read_labels(const std::string& path, const ParameterSection& params,
                                     uint64_t points) {
  // More than 255 labels do not fit one array (dimensions are bytes): LABELS2, LABELS3... continue.
  std::vector<std::string> labels;
  for (int part = 1; labels.size() < points; ++part) {
    const std::string key = part == 1 ? "POINT:LABELS" : "POINT:LABELS" + std::to_string(part);
    const auto more = params.strings(key);
    if (!more) break;
    labels.insert(labels.end(), more->begin(), more->end());
  }
  if (labels.size() < points)
    throw FileError(path, "POINT:LABELS holds " + std::to_string(labels.size()) + " labels for " +
                              std::to_string(points) + " points");
  labels.resize(points);
  return labels;
}

// Frame count and first frame. POINT:FRAMES is 16 bits; longer captures record the true range
// in TRIAL:ACTUAL_START_FIELD / ACTUAL_END_FIELD, each two 16-bit words (low, high).
void read_frame_range(const ParameterSection& params, const FilePrefix& prefix, Layout& layout) {
  const uint16_t header_first = layout.format.u16(prefix.at(kHeaderFirstFrame, 2, "header"));
  const uint16_t header_last = layout.format.u16(prefix.at(kHeaderLastFrame, 2, "header"));
  const auto frames_param = params.count("POINT:FRAMES");
  layout.frames =
      frames_param ? *frames_param : (header_last >= header_first ? header_last - header_first + 1 : 0);
  layout.first_frame = header_first;

  const auto field = [&](const std::string& key) -> std::optional<uint64_t> {
    const auto low = params.count(key, 0), high = params.count(key, 1);
    if (!low) return std::nullopt;
    return *low + (high ? *high : 0) * 65536;
  };
  const auto start = field("TRIAL:ACTUAL_START_FIELD"), end = field("TRIAL:ACTUAL_END_FIELD");
  if (!start || !end || *end < *start) return;
  const uint64_t trial_frames = *end - *start + 1;
  // Beyond what POINT:FRAMES can hold, which then says 65535 or the low 16 bits.
  if (trial_frames > 65535 && (layout.frames == 65535 || layout.frames == trial_frames % 65536))
    layout.frames = trial_frames;
  if (trial_frames == layout.frames) layout.first_frame = static_cast<int64_t>(*start);
}

uint64_t read_analog_words_per_frame(const std::string& path, const ParameterSection& params,
                                     const FilePrefix& prefix, const Layout& layout) {
  const uint16_t header_words = layout.format.u16(prefix.at(kHeaderAnalogWordsPerFrame, 2, "header"));
  const auto used = params.count("ANALOG:USED");
  if (!used) return header_words;
  if (*used == 0) return 0;
  uint64_t samples_per_frame = layout.format.u16(prefix.at(kHeaderAnalogSamplesPerFrame, 2, "header"));
  if (const auto analog_rate = params.number("ANALOG:RATE"); analog_rate && *analog_rate > 0) {
    const double ratio = *analog_rate / layout.rate;
    if (!(ratio >= 0.5 && ratio < 1e6) || std::abs(ratio - std::round(ratio)) > 1e-3 * ratio)
      throw FileError(path, "ANALOG:RATE " + text_of(*analog_rate) + " is not a multiple of POINT:RATE " +
                                text_of(layout.rate));
    samples_per_frame = static_cast<uint64_t>(std::round(ratio));
  }
  const uint64_t words = *used * samples_per_frame;
  // The header word is the same total; disagreeing means the frame size is unknowable.
  if (words % 65536 != header_words)
    throw FileError(path, "corrupt: header says " + std::to_string(header_words) +
                              " analog samples per frame, ANALOG parameters say " + std::to_string(words));
  return words;
}

Layout read_layout(const std::string& path, const FilePrefix& prefix, uint64_t file_size) {
  const uint8_t* header = prefix.at(0, 2, "header");
  if (header[1] != kHeaderKey)
    throw FileError(path,
                    "not a C3D file: header key byte is " + std::to_string(header[1]) + ", expected 80");
  const uint64_t parameter_block = header[0];
  if (parameter_block < 2)
    throw FileError(
        path, "bad parameter block pointer " + std::to_string(parameter_block) + " (must be 2 or more)");
  const uint64_t parameter_offset = (parameter_block - 1) * kBlockBytes;
  if (parameter_offset + 4 > file_size)
    throw FileError(path, "truncated or bad parameter block pointer " + std::to_string(parameter_block) +
                              ": parameters would start at byte " + std::to_string(parameter_offset) +
                              ", file holds " + std::to_string(file_size));
  const uint8_t* preamble = prefix.at(parameter_offset, 4, "parameter preamble");
  const uint64_t parameter_blocks = preamble[2];
  const int processor_byte = preamble[3];
  Layout layout;
  switch (processor_byte - kProcessorByteBase) {
    case 1:
      layout.format.processor = C3dProcessor::Intel;
      break;
    case 2:
      layout.format.processor = C3dProcessor::Dec;
      break;
    case 3:
      layout.format.processor = C3dProcessor::Mips;
      break;
    default:
      throw FileError(path, "unknown processor type " + std::to_string(processor_byte) +
                                " (expected 84 Intel, 85 DEC or 86 MIPS)");
  }
  if (parameter_blocks == 0) throw FileError(path, "corrupt: parameter section has 0 blocks");
  const uint64_t parameter_end = parameter_offset + parameter_blocks * kBlockBytes;
  if (parameter_end > file_size)
    throw FileError(path, "truncated: parameter section ends at byte " + std::to_string(parameter_end) +
                              ", file holds " + std::to_string(file_size));

  ParameterSection params(path, prefix, layout.format);
  params.parse(parameter_offset + 4, parameter_end);
  const WordFormat& f = layout.format;

  layout.points = params.count("POINT:USED").value_or(f.u16(prefix.at(kHeaderPointCount, 2, "header")));
  layout.labels = layout.points ? read_labels(path, params, layout.points) : std::vector<std::string>{};

  layout.rate = decimal_of(static_cast<float>(
      params.number("POINT:RATE").value_or(f.f32(prefix.at(kHeaderFrameRate, 4, "header")))));
  if (!(layout.rate > 0.0) || !std::isfinite(layout.rate))
    throw FileError(path, "bad frame rate " + text_of(layout.rate) + " (must be positive)");

  layout.scale =
      static_cast<float>(params.number("POINT:SCALE").value_or(f.f32(prefix.at(kHeaderScale, 4, "header"))));
  if (!std::isfinite(layout.scale) || (layout.scale == 0.0f && layout.points > 0))
    throw FileError(path, "corrupt: POINT:SCALE is " + text_of(layout.scale));
  // A negative scale selects float storage; its magnitude then only scales residuals.
  layout.float_storage = layout.scale < 0.0f;

  const auto units = params.strings("POINT:UNITS");
  layout.to_millimetres =
      static_cast<float>(unit_to_millimetres(path, units && !units->empty() ? units->front() : ""));

  read_frame_range(params, prefix, layout);
  if (layout.frames > static_cast<uint64_t>(std::numeric_limits<int>::max()))
    throw FileError(path, "too many frames: " + std::to_string(layout.frames));
  if (layout.first_frame > std::numeric_limits<int>::max())
    throw FileError(path, "first frame " + std::to_string(layout.first_frame) + " out of range");

  const uint64_t data_block =
      params.count("POINT:DATA_START").value_or(f.u16(prefix.at(kHeaderDataStart, 2, "header")));
  if (data_block < parameter_block + parameter_blocks)
    throw FileError(path, "corrupt: data start block " + std::to_string(data_block) +
                              " lies before the end of the parameter section (block " +
                              std::to_string(parameter_block + parameter_blocks) + ")");
  layout.data_offset = (data_block - 1) * kBlockBytes;
  layout.analog_words_per_frame = read_analog_words_per_frame(path, params, prefix, layout);

  const uint64_t frame_bytes = layout.frame_bytes();
  const uint64_t available = file_size > layout.data_offset ? file_size - layout.data_offset : 0;
  if (frame_bytes > 0 && available / frame_bytes < layout.frames)
    throw FileError(path, "truncated: parameters say " + std::to_string(layout.frames) + " frames of " +
                              std::to_string(frame_bytes) + " bytes, file holds " +
                              std::to_string(available / frame_bytes) + " whole frames");
  return layout;
}

// One point sample: raw words to millimetres, or missing.
template <typename Word>
Vec3 decode_sample(const Word (&word)[4], const Layout& layout) {
  if (word[3] < 0) return missing_point();  // negative residual: not reconstructed
  if (word[0] == 0 && word[1] == 0 && word[2] == 0) return missing_point();  // how some writers mark gaps
  // Scaled in float, the file's own precision, so a float round trip reproduces every value.
  const float factor = layout.float_storage ? layout.to_millimetres : layout.scale;
  Vec3 p;
  for (int axis = 0; axis < 3; ++axis) {
    float value = static_cast<float>(word[axis]) * factor;
    if (!layout.float_storage && layout.to_millimetres != 1.0f) value *= layout.to_millimetres;
    if (!std::isfinite(value)) return missing_point();
    p[axis] = value;
  }
  return p;
}

// Frames [first, first + count) of the data section, `count` whole frames at `frames`.
void decode_frames(const uint8_t* frames, uint64_t first, uint64_t count, const Layout& layout, Capture& capture) {
  const uint64_t frame_bytes = layout.frame_bytes();
  const WordFormat& f = layout.format;
  for (uint64_t i = 0; i < count; ++i) {
    const uint8_t* frame = frames + i * frame_bytes;
    for (uint64_t p = 0; p < layout.points; ++p) {
      Vec3& out = capture.at(static_cast<int>(first + i), static_cast<int>(p));
      if (layout.float_storage) {
        const uint8_t* b = frame + p * 16;
        const float word[4] = {f.f32(b), f.f32(b + 4), f.f32(b + 8), f.f32(b + 12)};
        out = decode_sample(word, layout);
      } else {
        const uint8_t* b = frame + p * 8;
        const int16_t word[4] = {f.i16(b), f.i16(b + 2), f.i16(b + 4), f.i16(b + 6)};
        out = decode_sample(word, layout);
      }
    }
  }
}

// The data section read from the file a few megabytes at a time (a take can be gigabytes).
void read_data(const std::string& path, std::ifstream& in, const Layout& layout, Capture& capture) {
  const uint64_t frame_bytes = layout.frame_bytes();
  if (layout.points == 0 || layout.frames == 0) return;
  in.seekg(static_cast<std::streamoff>(layout.data_offset));
  const uint64_t frames_per_chunk = std::max<uint64_t>(1, (4u << 20) / frame_bytes);
  std::vector<uint8_t> chunk;
  for (uint64_t first = 0; first < layout.frames; first += frames_per_chunk) {
    const uint64_t count = std::min(frames_per_chunk, layout.frames - first);
    chunk.resize(count * frame_bytes);
    if (!in.read(reinterpret_cast<char*>(chunk.data()), static_cast<std::streamsize>(chunk.size())))
      throw FileError(path, "read error in the data section at frame " + std::to_string(first));
    decode_frames(chunk.data(), first, count, layout, capture);
  }
}

Capture make_capture(const Layout& layout) {
  Capture capture(layout.labels, static_cast<int>(layout.frames), layout.rate);
  capture.first_frame = static_cast<int>(layout.first_frame);
  return capture;
}

}  // namespace

Capture read_c3d(const std::string& path) {
  std::error_code error;
  const auto status = std::filesystem::status(path, error);
  if (!std::filesystem::exists(status)) throw FileError(path, "no such file");
  if (!std::filesystem::is_regular_file(status)) throw FileError(path, "not a regular file");
  const uint64_t file_size = std::filesystem::file_size(path, error);
  if (error) throw FileError(path, "cannot read size: " + error.message());
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError(path, "cannot open for reading");
  if (file_size < kBlockBytes)
    throw FileError(
        path, "truncated: " + std::to_string(file_size) + " bytes, shorter than the 512-byte C3D header");

  std::vector<uint8_t> bytes(std::min(file_size, kMaxPrefixBytes));
  if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size())))
    throw FileError(path, "read error in the header or parameter section");
  const FilePrefix prefix(path, std::move(bytes));
  const Layout layout = read_layout(path, prefix, file_size);
  Capture capture = make_capture(layout);
  read_data(path, in, layout, capture);
  return capture;
}

Capture read_c3d_bytes(std::span<const uint8_t> bytes, const std::string& name) {
  if (bytes.size() < kBlockBytes)
    throw FileError(
        name, "truncated: " + std::to_string(bytes.size()) + " bytes, shorter than the 512-byte C3D header");
  const std::span<const uint8_t> kept = bytes.first(std::min<uint64_t>(bytes.size(), kMaxPrefixBytes));
  const FilePrefix prefix(name, std::vector<uint8_t>(kept.begin(), kept.end()));
  const Layout layout = read_layout(name, prefix, bytes.size());
  Capture capture = make_capture(layout);
  if (layout.points > 0 && layout.frames > 0)  // read_layout checked that the frames are all there
    decode_frames(bytes.data() + layout.data_offset, 0, layout.frames, layout, capture);
  return capture;
}

}  // namespace skinstream
