// The plan cache of studies: a PlanStore (calib/planning/plan_store.h) on files in a folder,
// one `<hash>.json` per planner input (hash: FNV-1a of PlanInputsText), holding that text and
// the plan with every number written exactly (the file format: bench/report/plan_file.h).
// Processes share it safely: the first one to miss takes an exclusive lock (flock on
// `<hash>.lock`) and plans, the others wait in Find and then read its plan, so concurrent
// trials with the same inputs plan once. A lock dies with its process (a killed trial leaves
// no stale lock); a file is written to a temporary name and renamed into place.
#pragma once

#include <atomic>
#include <map>
#include <mutex>
#include <string>

#include "calib/planning/plan_store.h"

namespace twin {

class FilePlanStore : public PlanStore {
 public:
  /// Uses (and creates) folder `dir`. Throws InputError naming it when it cannot be created.
  explicit FilePlanStore(std::string dir);
  ~FilePlanStore() override;
  FilePlanStore(const FilePlanStore&) = delete;
  FilePlanStore& operator=(const FilePlanStore&) = delete;

  std::optional<PosePlanResult> Find(const PlanInputs& inputs) override;
  void Store(const PlanInputs& inputs, const PosePlanResult& plan) override;
  void Abandon(const PlanInputs& inputs) override;

  /// The file a plan for `inputs` is kept in.
  std::string PathFor(const PlanInputs& inputs) const;
  int hits() const { return hits_.load(); }
  int misses() const { return misses_.load(); }

 private:
  void Unlock(const std::string& key);

  std::string dir_;
  std::mutex mutex_;                  // guards locks_ and the counters (threads of a run)
  std::map<std::string, int> locks_;  // hash -> fd of the held lock file
  std::atomic<int> hits_{0}, misses_{0};
};

}  // namespace twin
