// Reads TRC marker files. Layout (1-based lines):
//   1 PathFileType  4  (X/Y/Z)  name.trc
//   2 DataRate  CameraRate  NumFrames  NumMarkers  Units  OrigDataRate  OrigDataStartFrame  OrigNumFrames
//   3 the values of those keys
//   4 Frame#  Time  Name1  <empty>  <empty>  Name2 ...     (each name above its X column)
//   5 <empty> <empty> X1  Y1  Z1  X2 ...
//   then, after optional blank lines, one row per frame.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/files/file_error.h"
#include "protocol/files/trc.h"
#include "protocol/files/whole_file.h"

namespace skinstream {
namespace {

std::string lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string_view trim(std::string_view text) {
  const auto is_space = [](char c) { return c == ' ' || c == '\r' || c == '\n' || c == '\t'; };
  while (!text.empty() && is_space(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_space(text.back())) text.remove_suffix(1);
  return text;
}

std::vector<std::string_view> split_tabs(std::string_view line) {
  std::vector<std::string_view> cells;
  size_t start = 0;
  for (;;) {
    const size_t tab = line.find('\t', start);
    cells.push_back(
        trim(line.substr(start, tab == std::string_view::npos ? std::string_view::npos : tab - start)));
    if (tab == std::string_view::npos) return cells;
    start = tab + 1;
  }
}

// The file's lines, with line numbers kept for messages.
class TextLines {
 public:
  TextLines(const std::string& path, std::string text) : path_(path), text_(std::move(text)) {
    size_t start = 0;
    while (start < text_.size()) {
      size_t end = text_.find('\n', start);
      if (end == std::string::npos) end = text_.size();
      std::string_view line(text_.data() + start, end - start);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      lines_.push_back(line);
      start = end + 1;
    }
  }
  size_t size() const { return lines_.size(); }
  bool ends_with_line_break() const { return !text_.empty() && text_.back() == '\n'; }
  // Line `number` (1-based), or a FileError saying the file ends before `what`.
  std::string_view line(size_t number, const std::string& what) const {
    if (number > lines_.size())
      throw FileError(path_,
                      "truncated: file ends at line " + std::to_string(lines_.size()) + ", before " + what);
    return lines_[number - 1];
  }

 private:
  const std::string& path_;
  std::string text_;
  std::vector<std::string_view> lines_;
};

class CellParser {
 public:
  explicit CellParser(const std::string& path) : path_(path) {}

  double number(std::string_view cell, size_t line, size_t column) const {
    std::string_view text = cell;
    if (!text.empty() && text.front() == '+') text.remove_prefix(1);  // from_chars rejects a leading '+'
    double value = 0.0;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || error != std::errc() || end != text.data() + text.size())
      throw FileError(path_, "line " + std::to_string(line) + ", column " + std::to_string(column) + ": " +
                                 quoted_text(cell) + " is not a number");
    return value;
  }

  long long whole_number(std::string_view cell, size_t line, size_t column) const {
    const double value = number(cell, line, column);
    if (!(std::abs(value) < 9e15) || value != std::floor(value))
      throw FileError(path_, "line " + std::to_string(line) + ", column " + std::to_string(column) + ": " +
                                 quoted_text(cell) + " is not a whole number");
    return static_cast<long long>(value);
  }

 private:
  const std::string& path_;
};

double unit_to_millimetres(const std::string& path, std::string_view units) {
  const std::string u = lower(units);
  if (u == "mm") return 1.0;
  if (u == "cm") return 10.0;
  if (u == "dm") return 100.0;
  if (u == "m") return 1000.0;
  throw FileError(path, "unknown Units " + quoted_text(units) + " (expected mm, cm, dm or m)");
}

struct TrcHeader {
  double rate = 0.0;
  long long frames = 0;
  long long markers = 0;
  double to_millimetres = 1.0;
  std::optional<long long> start_frame;
};

constexpr size_t kKeyLine = 2, kValueLine = 3, kNameLine = 4, kAxisLine = 5;

TrcHeader read_header(const std::string& path, const TextLines& lines, const CellParser& parse) {
  if (lower(trim(lines.line(1, "the PathFileType line"))).rfind("pathfiletype", 0) != 0)
    throw FileError(path, "not a TRC file: line 1 does not start with PathFileType");
  const auto keys = split_tabs(lines.line(kKeyLine, "the header keys"));
  const auto values = split_tabs(lines.line(kValueLine, "the header values"));
  std::map<std::string, std::pair<std::string_view, size_t>> value_of;  // lower-case key -> value, column
  for (size_t i = 0; i < keys.size() && i < values.size(); ++i)
    if (!keys[i].empty()) value_of[lower(keys[i])] = {values[i], i + 1};
  const auto required = [&](const std::string& key, const std::string& name) {
    const auto it = value_of.find(key);
    if (it == value_of.end() || it->second.first.empty())
      throw FileError(path, "header has no " + name + " value");
    return it->second;
  };

  TrcHeader header;
  const auto [rate, rate_column] = required("datarate", "DataRate");
  header.rate = parse.number(rate, kValueLine, rate_column);
  if (!(header.rate > 0.0) || !std::isfinite(header.rate))
    throw FileError(path, "bad DataRate " + printable_text(rate, 40) + " (must be positive)");
  const auto [frames, frames_column] = required("numframes", "NumFrames");
  header.frames = parse.whole_number(frames, kValueLine, frames_column);
  const auto [markers, markers_column] = required("nummarkers", "NumMarkers");
  header.markers = parse.whole_number(markers, kValueLine, markers_column);
  if (header.frames < 0 || header.markers < 0 || header.frames > std::numeric_limits<int>::max())
    throw FileError(path, "bad NumFrames " + printable_text(frames, 40) + " or NumMarkers " + printable_text(markers, 40));
  header.to_millimetres = unit_to_millimetres(path, required("units", "Units").first);
  if (const auto it = value_of.find("origdatastartframe"); it != value_of.end() && !it->second.first.empty())
    header.start_frame = parse.whole_number(it->second.first, kValueLine, it->second.second);
  if (header.start_frame && std::abs(*header.start_frame) > std::numeric_limits<int>::max() / 2)
    throw FileError(path, "OrigDataStartFrame out of range");
  return header;
}

// Names sit above each marker's X column: columns 3, 6, 9... (1-based); nothing else may.
std::vector<std::string> read_names(const std::string& path, const TextLines& lines, long long markers) {
  const auto axes = split_tabs(lines.line(kAxisLine, "the X1 Y1 Z1 row"));
  const auto coordinate_columns = std::count_if(axes.begin() + std::min<size_t>(2, axes.size()), axes.end(),
                                                [](std::string_view c) { return !c.empty(); });
  if (coordinate_columns != 3 * markers)
    throw FileError(path, "line 5: " + std::to_string(coordinate_columns) +
                              " coordinate columns for NumMarkers " + std::to_string(markers));
  const auto cells = split_tabs(lines.line(kNameLine, "the marker name row"));
  if (lower(cells[0]) != "frame#")
    throw FileError(path, "line 4: expected the marker name row, starting with Frame#");
  std::vector<std::string> names(static_cast<size_t>(markers));
  for (size_t column = 2; column < cells.size(); ++column) {
    if (cells[column].empty()) continue;
    const size_t marker = (column - 2) / 3;
    if ((column - 2) % 3 != 0 || marker >= names.size())
      throw FileError(path, "line 4: marker name " + quoted_text(cells[column]) + " in column " +
                                std::to_string(column + 1) + " does not match NumMarkers " +
                                std::to_string(markers));
    names[marker] = std::string(cells[column]);
  }
  return names;
}

bool blank(std::string_view line) { return trim(line).empty(); }

Capture parse_trc(const std::string& path, std::string text) {
  const TextLines lines(path, std::move(text));
  const CellParser parse(path);

  const TrcHeader header = read_header(path, lines, parse);
  std::vector<std::string> names = read_names(path, lines, header.markers);

  size_t first_row = kAxisLine + 1;
  while (first_row <= lines.size() && blank(lines.line(first_row, "data"))) ++first_row;
  size_t last_row = lines.size();
  while (last_row >= first_row && blank(lines.line(last_row, "data"))) --last_row;
  const long long rows = static_cast<long long>(last_row + 1 - first_row);
  if (rows < header.frames)
    throw FileError(path, "truncated: NumFrames says " + std::to_string(header.frames) + ", file holds " +
                              std::to_string(rows) + " rows");
  if (rows > header.frames)
    throw FileError(path, "NumFrames says " + std::to_string(header.frames) + ", file holds " +
                              std::to_string(rows) + " rows");

  // Without its line break the last row may have lost digits ("-0.125" cut to "-0.1").
  if (header.frames > 0 && last_row == lines.size() && !lines.ends_with_line_break())
    throw FileError(path, "truncated: line " + std::to_string(last_row) + " has no line end");

  const size_t markers = names.size();
  const size_t columns = 2 + 3 * markers;
  Capture capture(std::move(names), static_cast<int>(header.frames), header.rate);
  capture.first_frame = static_cast<int>(header.start_frame.value_or(1));
  for (long long f = 0; f < header.frames; ++f) {
    const size_t line_number = first_row + static_cast<size_t>(f);
    const auto cells = split_tabs(lines.line(line_number, "frame " + std::to_string(f + 1)));
    const bool extra = std::any_of(cells.begin() + std::min(columns, cells.size()), cells.end(),
                                   [](std::string_view c) { return !c.empty(); });  // trailing tabs are fine
    if (cells.size() < columns || extra)
      throw FileError(path, "line " + std::to_string(line_number) + ": " + std::to_string(cells.size()) +
                                " columns, expected " + std::to_string(columns));
    const long long frame_number = parse.whole_number(cells[0], line_number, 1);
    if (std::abs(frame_number) > std::numeric_limits<int>::max() / 2)
      throw FileError(path, "line " + std::to_string(line_number) + ": frame number out of range");
    if (f == 0)
      capture.first_frame = static_cast<int>(frame_number);
    else if (frame_number != capture.first_frame + f)
      throw FileError(path, "line " + std::to_string(line_number) + ": frame number " +
                                std::to_string(frame_number) + ", expected " +
                                std::to_string(capture.first_frame + f));
    parse.number(cells[1], line_number, 2);  // time: must be a number, though frames define it
    for (size_t m = 0; m < markers; ++m) {
      const size_t column = 2 + 3 * m;
      const int empty = (cells[column].empty() ? 1 : 0) + (cells[column + 1].empty() ? 1 : 0) +
                        (cells[column + 2].empty() ? 1 : 0);
      if (empty == 3) continue;  // missing: stays NaN
      if (empty != 0)
        throw FileError(path, "line " + std::to_string(line_number) + ": marker " + std::to_string(m + 1) +
                                  " has only some of its coordinates");
      Vec3 p;
      for (int axis = 0; axis < 3; ++axis)
        p[axis] = parse.number(cells[column + axis], line_number, column + axis + 1) * header.to_millimetres;
      capture.at(static_cast<int>(f), static_cast<int>(m)) = is_present(p) ? p : missing_point();
    }
  }
  return capture;
}

}  // namespace

Capture read_trc(const std::string& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) throw FileError(path, "no such file");
  return parse_trc(path, read_whole_file(path));
}

Capture read_trc_bytes(std::string_view text, const std::string& name) { return parse_trc(name, std::string(text)); }

}  // namespace skinstream
