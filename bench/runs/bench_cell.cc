#include "bench/runs/bench_cell.h"

#include "bench/runs/recording_cell.h"
#include "bench/runs/replay_cell.h"
#include "calib/common/errors.h"

namespace twin {

namespace {

// The scenario's twin, built here and owned by the cell that drives it.
struct TwinHolder {
  TwinHolder(const TwinSpec& spec, const std::string& where)
      : twin(std::make_unique<TwinCell>(spec, where)) {}
  std::unique_ptr<TwinCell> twin;
};

class OwnedLocalTwinCell : private TwinHolder, public LocalTwinCell {
 public:
  OwnedLocalTwinCell(const TwinSpec& spec, const std::string& where)
      : TwinHolder(spec, where), LocalTwinCell(*twin) {}
};

}  // namespace

std::unique_ptr<BenchCell> OpenBenchCell(const TwinSpec& twin, const std::string& where,
                                         const CellOptions& options) {
  // A recording played back: no cell at all (a replay records nothing).
  if (!options.replay_dir.empty()) return std::make_unique<ReplayCell>(options.replay_dir);
  std::unique_ptr<BenchCell> cell;
  if (options.address.empty()) {
    cell = std::make_unique<OwnedLocalTwinCell>(twin, where);
  } else {
    throw InputError("--cell " + options.address, "remote cells are not available yet");
  }
  if (!options.record_dir.empty()) {
    cell = std::make_unique<RecordingCell>(std::move(cell), options.record_dir,
                                           options.record_info);
  }
  return cell;
}

}  // namespace twin
