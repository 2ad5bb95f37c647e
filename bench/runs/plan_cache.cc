#include "bench/runs/plan_cache.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "bench/io/content_hash.h"
#include "bench/io/model_loader.h"
#include "bench/io/output_files.h"
#include "bench/report/plan_file.h"
#include "calib/common/errors.h"

namespace twin {
FilePlanStore::FilePlanStore(std::string dir) : dir_(std::move(dir)) {
  // A new, empty or earlier plan cache (its mark), never a folder of the user's.
  ClaimOutputFolder(dir_, "--plan-cache", "plan-cache");
}

FilePlanStore::~FilePlanStore() {
  for (const auto& [key, fd] : locks_) close(fd);  // closing releases the flock
}

std::string FilePlanStore::PathFor(const PlanInputs& inputs) const {
  return dir_ + "/" + HashHex(Fnv1a64(PlanInputsText(inputs))) + ".json";
}

std::optional<PosePlanResult> FilePlanStore::Find(const PlanInputs& inputs) {
  const std::string text = PlanInputsText(inputs);
  const std::string key = HashHex(Fnv1a64(text));
  const std::string lock_path = dir_ + "/" + key + ".lock";
  Unlock(key);
  const int fd = open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError(lock_path, std::string("cannot open: ") + std::strerror(errno));
  while (flock(fd, LOCK_EX) != 0) {
    if (errno != EINTR) {
      close(fd);
      throw InputError(lock_path, std::string("cannot lock: ") + std::strerror(errno));
    }
  }
  const std::string path = dir_ + "/" + key + ".json";
  if (std::optional<PosePlanResult> plan = ReadPlanFile(path, text)) {
    close(fd);
    ++hits_;
    return plan;
  }
  // Missing, unreadable or foreign: planned again and overwritten in Store.
  {
    std::lock_guard<std::mutex> guard(mutex_);
    locks_[key] = fd;  // held until Store or Abandon: others wait for this plan
  }
  ++misses_;
  return std::nullopt;
}

void FilePlanStore::Store(const PlanInputs& inputs, const PosePlanResult& plan) {
  const std::string text = PlanInputsText(inputs);
  const std::string key = HashHex(Fnv1a64(text));
  WriteFileAtomically(dir_ + "/" + key + ".json", PlanFileText(text, plan));
  Unlock(key);
}

void FilePlanStore::Abandon(const PlanInputs& inputs) {
  Unlock(HashHex(Fnv1a64(PlanInputsText(inputs))));
}

void FilePlanStore::Unlock(const std::string& key) {
  std::lock_guard<std::mutex> guard(mutex_);
  const auto it = locks_.find(key);
  if (it == locks_.end()) return;
  close(it->second);
  locks_.erase(it);
}

}  // namespace twin
