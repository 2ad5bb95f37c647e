// RAII owners of MuJoCo objects (DESIGN.md, convention 10) and the loader of MJCF text.
#pragma once

#include <memory>
#include <string>

#include <mujoco/mujoco.h>

namespace twin {

struct MjModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using MjModelPtr = std::unique_ptr<mjModel, MjModelDeleter>;
using MjDataPtr = std::unique_ptr<mjData, MjDataDeleter>;

/// Compiles MJCF text through an in-memory VFS (no file is written). Throws std::runtime_error
/// with MuJoCo's message if the text does not compile (the text is ours, so that is a bug).
MjModelPtr LoadMjcfFromString(const std::string& mjcf);

/// Installs a MuJoCo warning/error handler that throws instead of printing (tests fail on any
/// MuJoCo warning, DESIGN.md convention 10). Idempotent.
void InstallMujocoErrorHandlers();

/// Number of MuJoCo warnings raised since the model's data was created.
int WarningCount(const mjData* d);

}  // namespace twin
