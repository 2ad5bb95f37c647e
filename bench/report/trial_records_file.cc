#include "bench/report/trial_records_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "bench/io/model_loader.h"
#include "bench/io/output_files.h"
#include "bench/io/yaml_util.h"
#include "calib/common/errors.h"

namespace twin {

// Largest trials.jsonl read: a record is 2-20 KB, so 1 GiB holds over 50000 trials.
constexpr std::uintmax_t kMaxTrialsFileBytes = std::uintmax_t{1} << 30;

namespace {

// Refuses a record whose fields have other types than MakeTrialRecord writes (a hand-edited or
// foreign file), so that no reader of the records meets a type it does not expect.
void CheckRecordTypes(const nlohmann::json& j, const std::string& where) {
  const auto need = [&](const char* key, bool ok, const char* what) {
    if (!ok) {
      throw InputError(where, std::string("field \"") + key + "\" must be " + what + ", got " +
                                  (j.contains(key) ? j[key].dump().substr(0, 60) : "nothing"));
    }
  };
  need("trial", j["trial"].get<long long>() >= 0 && j["trial"].get<long long>() < (1LL << 31),
       "a trial number from 0");
  need("status", !j.contains("status") || (j["status"].is_string() &&
                                            (j["status"] == "ok" || j["status"] == "failed")),
       "\"ok\" or \"failed\"");
  for (const char* key : {"scenario_hash", "scenario", "reason"}) {
    need(key, !j.contains(key) || j[key].is_string(), "a string");
  }
  need("exit_code", !j.contains("exit_code") || j["exit_code"].is_number_integer(), "an integer");
  need("seeds", !j.contains("seeds") || j["seeds"].is_object(), "an object");
  for (const char* key : {"figures", "labels", "run"}) {
    need(key, !j.contains(key) || j[key].is_object(), "an object");
  }
  if (j.contains("figures")) {
    for (const auto& [name, v] : j["figures"].items()) {
      if (!v.is_number() && !v.is_boolean()) {
        throw InputError(where, "figure \"" + name + "\" must be a number or a boolean, got " +
                                    v.dump().substr(0, 60));
      }
    }
  }
  if (j.contains("labels")) {
    for (const auto& [name, v] : j["labels"].items()) {
      if (!v.is_string()) {
        throw InputError(where, "label \"" + name + "\" must be a string, got " +
                                    v.dump().substr(0, 60));
      }
    }
  }
}

}  // namespace

TrialsFileContent ReadTrialsFile(const std::string& path) {
  TrialsFileContent out;
  std::error_code ec;
  const std::filesystem::file_status st = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(st)) return out;
  // A FIFO or a device would block or never end; a file past the limit is not a study's.
  RequireRegularFile(path, kMaxTrialsFileBytes);
  std::ifstream in(path, std::ios::binary);
  if (!in) return out;
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  std::size_t start = 0;
  int line = 0;
  while (start < text.size()) {
    ++line;
    const std::size_t end = text.find('\n', start);
    if (end == std::string::npos) {  // torn: the writer died before the newline
      out.torn_tail = true;
      break;
    }
    const std::string item = text.substr(start, end - start);
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(item);
    } catch (const std::exception& e) {
      throw InputError(path + ":" + std::to_string(line),
                       std::string("not a JSON trial record: ") + e.what());
    }
    if (!j.is_object() || !j.contains("trial") || !j["trial"].is_number_integer()) {
      throw InputError(path + ":" + std::to_string(line),
                       "not a trial record (a JSON object with an integer \"trial\")");
    }
    CheckRecordTypes(j, path + ":" + std::to_string(line));
    out.records.emplace_back(std::move(j));
    start = end + 1;
    out.valid_bytes = start;
  }
  return out;
}

void TruncateTrialsFile(const std::string& path, std::size_t size) {
  if (truncate(path.c_str(), static_cast<off_t>(size)) != 0) {
    throw InputError(path, std::string("cannot drop the torn last line: ") + std::strerror(errno));
  }
}

void AppendTrialRecord(const std::string& path, const TrialRecord& record) {
  const std::string line = record.document().dump() + "\n";
  const int fd = open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError(path, std::string("cannot open: ") + std::strerror(errno));
  if (!WriteAll(fd, line)) {
    const std::string why = std::strerror(errno);
    close(fd);
    throw InputError(path, "cannot append a trial: " + why);
  }
  if (fsync(fd) != 0) {
    const std::string why = std::strerror(errno);
    close(fd);
    throw InputError(path, "cannot flush a trial to the disk: " + why);
  }
  close(fd);
}

void WriteTrialsFile(const std::string& path, const std::vector<TrialRecord>& records) {
  std::string text;
  for (const TrialRecord& r : records) text += r.document().dump() + "\n";
  WriteFileAtomically(path, text);
}

}  // namespace twin
