// Loads a robot model from a file, choosing the format by extension (.yaml/.yml or .urdf).
#pragma once

#include <string>

#include "calib/kinematics/kinematic_model.h"

namespace twin {

/// Loads models/*.yaml or a URDF; any other extension is an InputError naming the path.
KinematicModel LoadRobotModel(const std::string& path);

/// Writes `text` to `path` atomically (a temporary file renamed into place), so a failure
/// never leaves a half-written file. Throws InputError naming the path on failure.
void WriteFileAtomically(const std::string& path, const std::string& text);

/// Creates the empty staging folder `out` + ".partial" (a left-over one is removed first) and
/// returns its path; PublishDirectory moves it onto `out` when the output is complete. Throws
/// InputError naming `out` when it cannot be created.
std::string CreateStagingDirectory(const std::string& out);

/// Replaces the folder `out` by the completed folder `staging` (renamed into place; an old
/// `out` is kept aside until then), so readers never see a half-written output folder.
void PublishDirectory(const std::string& staging, const std::string& out);

}  // namespace twin
