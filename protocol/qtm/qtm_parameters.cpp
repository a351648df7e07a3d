#include "protocol/qtm/qtm_parameters.h"

#include <expat.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <memory>

#include "protocol/printable_text.h"

namespace skinstream::qtm {
namespace {

void append_escaped(std::string& out, std::string_view text) {
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
}

std::string number_text(double value) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return ec == std::errc() ? std::string(buffer, end) : "0";
}

constexpr size_t kMaxTextBytes = 1024;  // a label or a number; QTM's own are far shorter
constexpr size_t kMaxLabels = 100'000;  // QTM tracks a few thousand at most

// What the parser is inside of; only the elements read are tracked, by their depth.
struct ParseState {
  Parameters* out = nullptr;
  int depth = 0;           // of the element now open (the root is 1)
  int general_depth = 0;   // depth of <General>, 0 when outside it
  int the_3d_depth = 0;    // depth of <The_3D>
  bool in_label = false;
  std::string text;        // character data of the innermost element
  long declared_labels = -1;
  std::string error;
};

bool is(const XML_Char* name, const char* wanted) { return std::strcmp(name, wanted) == 0; }

void XMLCALL on_start(void* user, const XML_Char* name, const XML_Char**) {
  auto& s = *static_cast<ParseState*>(user);
  ++s.depth;
  s.text.clear();
  if (s.depth == 2 && is(name, "General")) s.general_depth = 2;
  if (s.depth == 2 && is(name, "The_3D")) {
    s.the_3d_depth = 2;
    s.out->has_3d = true;
  }
  if (s.the_3d_depth == 2 && s.depth == 3 && is(name, "Label")) s.in_label = true;
}

bool parse_number(const std::string& text, double& out) {
  const char* begin = text.data();
  const char* end = begin + text.size();
  while (begin < end && (*begin == ' ' || *begin == '\n' || *begin == '\r' || *begin == '\t')) ++begin;
  while (end > begin && (end[-1] == ' ' || end[-1] == '\n' || end[-1] == '\r' || end[-1] == '\t')) --end;
  const auto [stop, ec] = std::from_chars(begin, end, out);
  return ec == std::errc() && stop == end && std::isfinite(out);
}

void XMLCALL on_end(void* user, const XML_Char* name) {
  auto& s = *static_cast<ParseState*>(user);
  if (s.general_depth == 2 && s.depth == 3) {
    if (is(name, "Frequency") && (!parse_number(s.text, s.out->frequency_hz) || s.out->frequency_hz < 0.0))
      s.error = "General/Frequency is not a frequency: " + quoted_text(s.text);
    if (is(name, "Capture_Time")) parse_number(s.text, s.out->capture_time_s);
  }
  if (s.the_3d_depth == 2 && s.depth == 3) {
    if (is(name, "AxisUpwards")) s.out->axis_upwards = s.text;
    if (is(name, "Labels")) {
      double count = 0;
      if (!parse_number(s.text, count) || count < 0 || count != std::floor(count))
        s.error = "The_3D/Labels is not a count: " + quoted_text(s.text);
      else if (count > static_cast<double>(kMaxLabels))  // and beyond a long's range, not converted
        s.error = "The_3D/Labels says " + quoted_text(s.text) + ", more than " + std::to_string(kMaxLabels) + " labels";
      else
        s.declared_labels = static_cast<long>(count);
    }
    if (is(name, "Label")) s.in_label = false;
  }
  if (s.in_label && s.depth == 4 && is(name, "Name")) {
    if (s.out->labels.size() >= kMaxLabels && s.error.empty())
      s.error = "The_3D names more than " + std::to_string(kMaxLabels) + " labels";
    else
      s.out->labels.push_back(s.text);
  }
  if (s.depth == 2) s.general_depth = s.the_3d_depth = 0;
  s.text.clear();
  --s.depth;
}

void XMLCALL on_text(void* user, const XML_Char* text, int length) {
  auto& s = *static_cast<ParseState*>(user);
  if (s.text.size() + static_cast<size_t>(length) > kMaxTextBytes) {
    if (s.error.empty()) s.error = "an element's text is longer than " + std::to_string(kMaxTextBytes) + " bytes";
    return;
  }
  s.text.append(text, static_cast<size_t>(length));
}

}  // namespace

std::string write_parameters_xml(const Parameters& p, int minor_version) {
  const std::string root = "QTM_Parameters_Ver_1." + std::to_string(minor_version);
  std::string xml = "<" + root + ">\n";
  if (p.frequency_hz > 0.0) {
    xml += "  <General>\n    <Frequency>" + number_text(p.frequency_hz) + "</Frequency>\n";
    xml += "    <Capture_Time>" + number_text(p.capture_time_s) + "</Capture_Time>\n  </General>\n";
  }
  if (p.has_3d) {
    xml += "  <The_3D>\n    <AxisUpwards>";
    append_escaped(xml, p.axis_upwards);
    xml += "</AxisUpwards>\n    <CalibrationTime></CalibrationTime>\n";
    xml += "    <Labels>" + std::to_string(p.labels.size()) + "</Labels>\n";
    for (const std::string& label : p.labels) {
      xml += "    <Label>\n      <Name>";
      append_escaped(xml, label);
      xml += "</Name>\n      <RGBColor>16711680</RGBColor>\n    </Label>\n";
    }
    xml += "  </The_3D>\n";
  }
  xml += "</" + root + ">\n";
  return xml;
}

bool parse_parameters_xml(std::string_view xml, Parameters& out, std::string& out_error) {
  out = Parameters{};
  out.has_3d = false;
  std::unique_ptr<XML_ParserStruct, decltype(&XML_ParserFree)> parser(XML_ParserCreate("UTF-8"), XML_ParserFree);
  if (!parser) {
    out_error = "cannot create an XML parser";
    return false;
  }
  ParseState state;
  state.out = &out;
  XML_SetUserData(parser.get(), &state);
  XML_SetElementHandler(parser.get(), on_start, on_end);
  XML_SetCharacterDataHandler(parser.get(), on_text);
  if (xml.size() > static_cast<size_t>(INT32_MAX)) {
    out_error = "XML document too large";
    return false;
  }
  if (XML_Parse(parser.get(), xml.data(), static_cast<int>(xml.size()), XML_TRUE) != XML_STATUS_OK) {
    out_error = std::string("parameters XML, line ") + std::to_string(XML_GetCurrentLineNumber(parser.get())) +
                ": " + XML_ErrorString(XML_GetErrorCode(parser.get()));
    return false;
  }
  if (!state.error.empty()) {
    out_error = state.error;
    return false;
  }
  if (state.declared_labels >= 0 && static_cast<size_t>(state.declared_labels) != out.labels.size()) {
    out_error = "The_3D says " + std::to_string(state.declared_labels) + " labels but names " +
                std::to_string(out.labels.size());
    return false;
  }
  return true;
}

}  // namespace skinstream::qtm
