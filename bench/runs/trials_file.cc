#include "bench/runs/trials_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "bench/io/model_loader.h"
#include "calib/common/errors.h"

namespace twin {

TrialsFileContent ReadTrialsFile(const std::string& path) {
  TrialsFileContent out;
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
    out.records.push_back(std::move(j));
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

void AppendTrialRecord(const std::string& path, const nlohmann::json& record) {
  const std::string line = record.dump() + "\n";
  const int fd = open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError(path, std::string("cannot open: ") + std::strerror(errno));
  std::size_t done = 0;
  while (done < line.size()) {
    const ssize_t n = write(fd, line.data() + done, line.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = std::strerror(errno);
      close(fd);
      throw InputError(path, "cannot append a trial: " + why);
    }
    done += static_cast<std::size_t>(n);
  }
  if (fsync(fd) != 0) {
    const std::string why = std::strerror(errno);
    close(fd);
    throw InputError(path, "cannot flush a trial to the disk: " + why);
  }
  close(fd);
}

void WriteTrialsFile(const std::string& path, const std::vector<nlohmann::json>& records) {
  std::string text;
  for (const nlohmann::json& r : records) text += r.dump() + "\n";
  WriteFileAtomically(path, text);
}

}  // namespace twin
