#include "protocol/qtm/qtm_command.h"

#include <charconv>

#include "protocol/printable_text.h"

namespace skinstream::qtm {
namespace {

std::vector<std::string_view> split_words(std::string_view text) {
  std::vector<std::string_view> words;
  size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t' || text[i] == '\r' || text[i] == '\n')) ++i;
    const size_t start = i;
    while (i < text.size() && text[i] != ' ' && text[i] != '\t' && text[i] != '\r' && text[i] != '\n') ++i;
    if (i > start) words.push_back(text.substr(start, i - start));
  }
  return words;
}

bool parse_uint(std::string_view text, uint32_t& out) {
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc() && end == text.data() + text.size() && !text.empty();
}

bool starts_with_word(std::string_view text, std::string_view prefix) {
  return text.size() >= prefix.size() && same_word(text.substr(0, prefix.size()), prefix);
}

bool fail(std::string& out_error, std::string reason) {
  out_error = std::move(reason);
  return false;
}

// "UDP:5000" or "UDP:10.0.0.2:5000" (the word starts with "UDP").
bool parse_udp(std::string_view word, Command& out, std::string& out_error) {
  const std::string_view rest = word.size() > 3 && word[3] == ':' ? word.substr(4) : std::string_view();
  const size_t colon = rest.rfind(':');
  const std::string_view port = colon == std::string_view::npos ? rest : rest.substr(colon + 1);
  uint32_t value = 0;
  if (!parse_uint(port, value) || value == 0 || value > 65535)
    return fail(out_error, "StreamFrames: bad UDP port in " + quoted_text(word));
  out.udp = true;
  out.udp_port = static_cast<uint16_t>(value);
  out.udp_address = colon == std::string_view::npos ? std::string() : std::string(rest.substr(0, colon));
  return true;
}

bool parse_stream_frames(const std::vector<std::string_view>& words, Command& out, std::string& out_error) {
  if (words.size() == 2 && same_word(words[1], "Stop")) {
    out.kind = Command::Kind::StreamFramesStop;
    return true;
  }
  if (words.size() < 2) return fail(out_error, "StreamFrames needs a rate and components");
  const std::string_view rate = words[1];
  if (same_word(rate, "AllFrames")) {
    out.rate = Command::Rate::AllFrames;
  } else {
    const bool divisor = starts_with_word(rate, "FrequencyDivisor:");
    const bool frequency = !divisor && starts_with_word(rate, "Frequency:");
    const size_t colon = rate.find(':');
    if ((!divisor && !frequency) || !parse_uint(rate.substr(colon + 1), out.rate_value) || out.rate_value == 0)
      return fail(out_error, "StreamFrames: bad rate " + quoted_text(rate));
    out.rate = divisor ? Command::Rate::FrequencyDivisor : Command::Rate::Frequency;
  }
  for (size_t i = 2; i < words.size(); ++i) {
    if (starts_with_word(words[i], "UDP") && (words[i].size() == 3 || words[i][3] == ':')) {
      if (!parse_udp(words[i], out, out_error)) return false;
    } else {
      out.components.emplace_back(words[i]);
    }
  }
  if (out.components.empty()) return fail(out_error, "StreamFrames names no component");
  out.kind = Command::Kind::StreamFrames;
  return true;
}

}  // namespace

bool same_word(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    const auto lower = [](char c) { return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c; };
    if (lower(a[i]) != lower(b[i])) return false;
  }
  return true;
}

bool parse_command(std::string_view text, Command& out, std::string& out_error) {
  out = Command{};
  const std::vector<std::string_view> words = split_words(text);
  if (words.empty()) return fail(out_error, "empty command");
  out.word = std::string(words[0]);
  const std::string_view word = words[0];
  if (same_word(word, "Version")) {
    out.kind = Command::Kind::Version;
    if (words.size() == 1) return true;
    const std::string_view v = words[1];
    const size_t dot = v.find('.');
    uint32_t major = 0, minor = 0;
    if (words.size() != 2 || dot == std::string_view::npos || !parse_uint(v.substr(0, dot), major) ||
        !parse_uint(v.substr(dot + 1), minor) || major > 99 || minor > 99)
      return fail(out_error, "Version: bad version " + quoted_text(text));
    out.major = static_cast<int>(major);
    out.minor = static_cast<int>(minor);
    return true;
  }
  if (same_word(word, "StreamFrames")) return parse_stream_frames(words, out, out_error);
  if (same_word(word, "GetState")) out.kind = Command::Kind::GetState;
  if (same_word(word, "QTMVersion")) out.kind = Command::Kind::QtmVersion;
  if (same_word(word, "ByteOrder")) out.kind = Command::Kind::ByteOrder;
  const bool parameters = same_word(word, "GetParameters");
  if (parameters || same_word(word, "GetCurrentFrame")) {
    out.kind = parameters ? Command::Kind::GetParameters : Command::Kind::GetCurrentFrame;
    for (size_t i = 1; i < words.size(); ++i) out.components.emplace_back(words[i]);
  }
  return true;
}

std::string stream_frames_command(const std::vector<std::string>& components, uint16_t udp_port) {
  std::string text = "StreamFrames AllFrames";
  if (udp_port > 0) text += " UDP:" + std::to_string(udp_port);
  for (const std::string& c : components) text += " " + c;
  return text;
}

}  // namespace skinstream::qtm
