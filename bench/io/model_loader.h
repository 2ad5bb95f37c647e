// Loads a robot model from a file, choosing the format by extension (.yaml/.yml or .urdf).
#pragma once

#include <string>
#include <vector>

#include "calib/kinematics/kinematic_model.h"

namespace twin {

/// Where a URDF's arm starts and ends (bench/io/urdf_model.h): `--base-link` / `--tip-link`
/// of the CLI, `base_link` / `tip_link` of a scenario's robot entry. Empty: the URDF's root and
/// its automatic tip. Given for a YAML model, they are an InputError (a YAML model is one chain).
struct ModelLinks {
  std::string base_link;
  std::string tip_link;
};

/// Loads models/*.yaml or a URDF; any other extension is an InputError naming the path.
/// `warnings` (optional) receives the URDF import's warnings (ParseUrdf).
KinematicModel LoadRobotModel(const std::string& path, const ModelLinks& links = {},
                              std::vector<std::string>* warnings = nullptr);

/// Prints each warning to stderr as "warning: ...".
void PrintWarnings(const std::vector<std::string>& warnings);

/// LoadRobotModel, printing its warnings (the CLI verbs that take a model file).
KinematicModel LoadRobotModelAndWarn(const std::string& path, const ModelLinks& links = {});

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
