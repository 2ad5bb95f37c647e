#include "bench/report/recording_file.h"

#include <algorithm>
#include <cctype>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "calib/common/errors.h"

namespace twin {
using Json = nlohmann::ordered_json;

namespace {

// --- the raw text of a JSON object's members ----------------------------------------------
// The request and response of a line are handed on as the very text protobuf printed: a
// re-print (nlohmann reads "-0" as the integer 0) could change a double's bits.

size_t SkipSpace(const std::string& s, size_t i) {
  while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
  return i;
}

// One past the closing quote of the string that starts at s[i].
size_t SkipString(const std::string& s, size_t i) {
  for (++i; i < s.size(); ++i) {
    if (s[i] == '\\') {
      ++i;
    } else if (s[i] == '"') {
      return i + 1;
    }
  }
  return s.size();
}

// One past the end of the JSON value that starts at s[i] (the text is valid JSON).
size_t SkipValue(const std::string& s, size_t i) {
  if (i < s.size() && s[i] == '"') return SkipString(s, i);
  if (i < s.size() && (s[i] == '{' || s[i] == '[')) {
    int depth = 0;
    while (i < s.size()) {
      const char c = s[i];
      if (c == '"') {
        i = SkipString(s, i);
        continue;
      }
      if (c == '{' || c == '[') ++depth;
      if ((c == '}' || c == ']') && --depth == 0) return i + 1;
      ++i;
    }
    return s.size();
  }
  while (i < s.size() && s[i] != ',' && s[i] != '}' && s[i] != ']' &&
         !std::isspace(static_cast<unsigned char>(s[i]))) {
    ++i;
  }
  return i;
}

// The members of the object text `s` (valid JSON): each key (unquoted, as written) and the raw
// text of its value.
std::vector<std::pair<std::string, std::string>> RawMembers(const std::string& s) {
  std::vector<std::pair<std::string, std::string>> members;
  size_t i = SkipSpace(s, 0);
  if (i >= s.size() || s[i] != '{') return members;
  i = SkipSpace(s, i + 1);
  while (i < s.size() && s[i] == '"') {
    const size_t key_end = SkipString(s, i);
    std::string key = s.substr(i + 1, key_end - i - 2);
    i = SkipSpace(s, key_end);
    if (i < s.size() && s[i] == ':') i = SkipSpace(s, i + 1);
    const size_t value_end = SkipValue(s, i);
    members.emplace_back(std::move(key), s.substr(i, value_end - i));
    i = SkipSpace(s, value_end);
    if (i < s.size() && s[i] == ',') i = SkipSpace(s, i + 1);
  }
  return members;
}

// The object text of `members` without `drop`.
std::string ObjectText(const std::vector<std::pair<std::string, std::string>>& members,
                       const std::string& drop) {
  std::string text = "{";
  for (const auto& [key, value] : members) {
    if (key == drop) continue;
    if (text.size() > 1) text += ',';
    text += "\"" + key + "\":" + value;
  }
  return text + "}";
}

template <typename T>
T Get(const Json& j, const char* key, const std::string& where) {
  if (!j.contains(key)) throw InputError(where, std::string("no \"") + key + "\"");
  try {
    return j.at(key).get<T>();
  } catch (const Json::exception&) {
    throw InputError(where, std::string("\"") + key + "\" has the wrong type: " +
                                j.at(key).dump());
  }
}

template <typename T>
T GetOr(const Json& j, const char* key, T fallback, const std::string& where) {
  return j.contains(key) ? Get<T>(j, key, where) : fallback;
}

}  // namespace

std::string RecordingManifestText(const RecordingManifest& m) {
  Json j;
  j["format"] = kRecordingFormat;
  j["version"] = kRecordingVersion;
  j["protocol"] = kRecordingProtocol;
  j["twinbench"] = m.twinbench;
  j["started_utc"] = m.started_utc;
  j["complete"] = m.complete;
  if (m.complete) {
    j["ended_utc"] = m.ended_utc;
    j["exchanges"] = m.exchanges;
  }
  j["scenario"] = {{"path", m.scenario_path}, {"folder", m.scenario_dir},
                   {"content", m.scenario_text}};
  j["trial"] = m.trial;
  j["options"] = {{"diagnosis", m.diagnosis}, {"images", m.images},
                  {"plan_cache", m.plan_cache}, {"cell", m.cell}};
  return j.dump(2) + "\n";
}

RecordingManifest ParseRecordingManifest(const std::string& text, const std::string& where) {
  Json j;
  try {
    j = Json::parse(text);
  } catch (const Json::exception& e) {
    throw InputError(where, std::string("not JSON: ") + e.what());
  }
  if (!j.is_object() || GetOr<std::string>(j, "format", "", where) != kRecordingFormat) {
    throw InputError(where, std::string("not a recording (\"format\": \"") + kRecordingFormat +
                                "\" expected)");
  }
  const int version = Get<int>(j, "version", where);
  if (version < 1 || version > kRecordingVersion) {
    throw InputError(where, "recording format version " + std::to_string(version) +
                                "; this twinbench reads version " +
                                std::to_string(kRecordingVersion));
  }
  RecordingManifest m;
  m.twinbench = GetOr<std::string>(j, "twinbench", "", where);
  m.started_utc = GetOr<std::string>(j, "started_utc", "", where);
  m.complete = GetOr<bool>(j, "complete", false, where);
  m.ended_utc = GetOr<std::string>(j, "ended_utc", "", where);
  m.exchanges = GetOr<long>(j, "exchanges", 0, where);
  const Json scenario = Get<Json>(j, "scenario", where);
  m.scenario_path = Get<std::string>(scenario, "path", where + " scenario");
  m.scenario_dir = Get<std::string>(scenario, "folder", where + " scenario");
  m.scenario_text = Get<std::string>(scenario, "content", where + " scenario");
  m.trial = Get<int>(j, "trial", where);
  const Json options = Get<Json>(j, "options", where);
  m.diagnosis = GetOr<bool>(options, "diagnosis", true, where + " options");
  m.images = GetOr<bool>(options, "images", true, where + " options");
  m.plan_cache = GetOr<std::string>(options, "plan_cache", "", where + " options");
  m.cell = GetOr<std::string>(options, "cell", "", where + " options");
  return m;
}

std::string RecordedExchangeLine(const RecordedExchange& e) {
  std::string response = e.response_json;
  if (!e.image_file.empty()) {
    // The image's file as the response's last member, in place of the bytes.
    const size_t close = response.rfind('}');
    const bool empty = RawMembers(response).empty();
    response = response.substr(0, close) + (empty ? "" : ",") + "\"image_file\":" +
               Json(e.image_file).dump() + "}";
  }
  // The seq, method and time through the JSON library; request and response as printed.
  Json head;
  head["seq"] = e.seq;
  head["method"] = e.method;
  head["t_wall_s"] = e.t_wall_s;
  std::string line = head.dump();
  line.pop_back();
  return line + ",\"request\":" + e.request_json + ",\"response\":" + response + "}";
}

RecordedExchange ParseRecordedExchangeLine(const std::string& line, const std::string& where) {
  Json j;
  try {
    j = Json::parse(line);
  } catch (const Json::exception& e) {
    throw InputError(where, std::string("not a JSON line: ") + e.what());
  }
  if (!j.is_object()) throw InputError(where, "not a JSON object");
  RecordedExchange e;
  e.seq = Get<long>(j, "seq", where);
  e.method = Get<std::string>(j, "method", where);
  e.t_wall_s = GetOr<double>(j, "t_wall_s", 0.0, where);
  if (!j.contains("request") || !j["request"].is_object() || !j.contains("response") ||
      !j["response"].is_object()) {
    throw InputError(where, "expected \"request\" and \"response\" objects");
  }
  const Json& response = j["response"];
  if (response.contains("image_file")) {
    e.image_file = Get<std::string>(response, "image_file", where);
    // A file of the recording's images/ folder, never a path out of it.
    const std::string folder = std::string(kRecordingImagesFolder) + "/";
    const std::string name = e.image_file.substr(std::min(folder.size(), e.image_file.size()));
    if (e.image_file.compare(0, folder.size(), folder) != 0 || name.empty() ||
        name.find('/') != std::string::npos || name.find('\\') != std::string::npos ||
        name == "." || name == "..") {
      throw InputError(where, "image_file '" + e.image_file + "' is not a file of the "
                              "recording's " + folder + " folder");
    }
  }
  for (const auto& [key, value] : RawMembers(line)) {
    if (key == "request") e.request_json = value;
    if (key == "response") e.response_json = ObjectText(RawMembers(value), "image_file");
  }
  return e;
}

}  // namespace twin
