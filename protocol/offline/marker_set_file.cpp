#include "protocol/offline/marker_set_file.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>

#include "protocol/files/file_error.h"
#include "protocol/files/whole_file.h"

namespace skinstream {

namespace {

using nlohmann::json;

// A definition file is a few kilobytes; anything far larger is not one.
constexpr std::uintmax_t kMaxFileBytes = 4u << 20;

// Parses, refusing a key repeated within one object (nlohmann would keep the last silently).
json parse_strict(const std::string& text, const std::string& path) {
  std::vector<std::set<std::string>> keys;
  std::string repeated;
  const json::parser_callback_t callback = [&](int, json::parse_event_t event, json& parsed) {
    if (event == json::parse_event_t::object_start) keys.emplace_back();
    if (event == json::parse_event_t::object_end && !keys.empty()) keys.pop_back();
    if (event == json::parse_event_t::key && !keys.empty() &&
        !keys.back().insert(parsed.get<std::string>()).second && repeated.empty())
      repeated = parsed.get<std::string>();
    return true;
  };
  json doc;
  try {
    doc = json::parse(text, callback);
  } catch (const json::exception& e) {
    throw FileError(path, std::string("not valid JSON: ") + e.what());
  }
  if (!repeated.empty())
    throw FileError(path, "key " + quoted_text(repeated) + " appears twice in one object");
  return doc;
}

// Reads fields of one JSON object, naming `where` in every complaint and refusing the keys it
// was not asked for.
class Fields {
 public:
  Fields(const json& object, std::string where, const std::string& path)
      : object_(object), where_(std::move(where)), path_(path) {
    if (!object_.is_object()) fail("must be a JSON object");
  }

  bool has(const char* key) const { return object_.contains(key); }

  std::string text(const char* key, bool required) {
    seen_.insert(key);
    if (!object_.contains(key)) {
      if (required) fail(std::string("has no \"") + key + "\"");
      return {};
    }
    const json& v = object_.at(key);
    if (!v.is_string()) fail(std::string("\"") + key + "\" must be a string");
    return v.get<std::string>();
  }

  std::vector<std::string> texts(const char* key, bool required) {
    seen_.insert(key);
    if (!object_.contains(key)) {
      if (required) fail(std::string("has no \"") + key + "\"");
      return {};
    }
    const json& v = object_.at(key);
    if (!v.is_array()) fail(std::string("\"") + key + "\" must be an array of strings");
    std::vector<std::string> out;
    for (const json& item : v) {
      if (!item.is_string()) fail(std::string("\"") + key + "\" must be an array of strings");
      out.push_back(item.get<std::string>());
    }
    return out;
  }

  double number(const char* key, double fallback) {
    seen_.insert(key);
    if (!object_.contains(key)) return fallback;
    return finite(object_.at(key), std::string("\"") + key + "\" must be a finite number");
  }

  Vec3 vector3(const char* key) {
    seen_.insert(key);
    const std::string problem = std::string("\"") + key + "\" must be 3 finite numbers";
    if (!object_.contains(key)) fail(std::string("has no \"") + key + "\"");
    const json& v = object_.at(key);
    if (!v.is_array() || v.size() != 3) fail(problem);
    return Vec3(finite(v[0], problem), finite(v[1], problem), finite(v[2], problem));
  }

  const json& array(const char* key) {
    seen_.insert(key);
    if (!object_.contains(key)) fail(std::string("has no \"") + key + "\"");
    const json& v = object_.at(key);
    if (!v.is_array()) fail(std::string("\"") + key + "\" must be an array");
    return v;
  }

  // After all reads: a key nobody asked for is a typo or a field of another kind of entry.
  void no_other_keys() const {
    for (const auto& item : object_.items())
      if (!seen_.count(item.key())) fail("unknown key " + quoted_text(item.key()));
  }

  [[noreturn]] void fail(const std::string& what) const { throw FileError(path_, where_ + ": " + what); }

 private:
  double finite(const json& v, const std::string& problem) const {
    if (!v.is_number()) fail(problem);
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(problem);
    return x;
  }

  const json& object_;
  std::string where_;
  const std::string& path_;
  std::set<std::string> seen_;
};

int parse_side(const std::string& side, const Fields& fields) {
  if (side.empty() || side == "any") return kAnySide;
  if (side == "front") return kFrontSide;
  if (side == "back") return kBackSide;
  fields.fail("\"side\" must be \"front\", \"back\" or \"any\", not " + quoted_text(side));
}

MarkerPlacement read_entry(const json& entry, const std::string& where, const std::string& path) {
  Fields f(entry, where, path);
  MarkerPlacement p;
  if (f.has("pattern") == f.has("name"))
    f.fail("needs either \"name\" (one marker) or \"pattern\" (a region)");
  p.description = f.text("description", false);
  if (f.has("pattern")) {
    p.pattern = f.text("pattern", true);
    p.bones = f.texts("bones", true);
    p.side = parse_side(f.text("side", false), f);
  } else {
    p.name = f.text("name", true);
    p.aliases = f.texts("aliases", false);
    p.bone = f.text("bone", true);
    p.along = f.number("along", p.along);
    p.direction = f.vector3("direction");
    if (p.direction.norm() < 1e-9) f.fail("\"direction\" must not be zero");
    p.direction.normalize();
    p.radius_mm = f.number("radius_mm", p.radius_mm);
  }
  f.no_other_keys();
  return p;
}

std::string lowered(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

MarkerSet read_marker_set(const std::string& path) {
  const json doc = parse_strict(read_whole_file(path, {kMaxFileBytes, "marker set"}), path);
  Fields top(doc, "the marker set", path);
  MarkerSet set;
  set.name = top.text("name", true);
  set.source = top.text("source", true);
  top.text("notes", false);
  const std::string set_where = "marker set " + quoted_text(set.name);
  const json& markers = top.array("markers");
  top.no_other_keys();
  for (size_t i = 0; i < markers.size(); ++i) {
    const json& e = markers[i];
    std::string label;
    if (e.is_object())
      for (const char* key : {"name", "pattern"})
        if (e.contains(key) && e.at(key).is_string())
          label = " (" + printable_text(e.at(key).get<std::string>(), 40) + ")";
    set.markers.push_back(read_entry(e, set_where + " entry " + std::to_string(i + 1) + label, path));
  }
  try {
    validate(set);
  } catch (const std::invalid_argument& e) {
    throw FileError(path, e.what());
  }
  return set;
}

std::vector<MarkerSet> read_marker_sets(const std::string& folder) {
  std::vector<std::string> paths;
  std::error_code ec;
  std::filesystem::directory_iterator it(folder, ec);
  if (ec) throw FileError(folder, "cannot read the folder: " + ec.message());
  for (const auto& entry : it) {
    const std::filesystem::path& p = entry.path();
    if (p.extension() == ".json" && entry.is_regular_file(ec)) paths.push_back(p.string());
  }
  if (paths.empty()) throw FileError(folder, "holds no marker set (*.json)");
  std::sort(paths.begin(), paths.end());
  std::vector<MarkerSet> sets;
  std::vector<std::string> names;
  for (const std::string& path : paths) {
    sets.push_back(read_marker_set(path));
    const std::string key = lowered(sets.back().name);
    const auto same = std::find(names.begin(), names.end(), key);
    if (same != names.end())
      throw FileError(path, "marker set " + quoted_text(sets.back().name) + " is also defined in " +
                                paths[static_cast<size_t>(same - names.begin())]);
    names.push_back(key);
  }
  return sets;
}

}  // namespace skinstream
