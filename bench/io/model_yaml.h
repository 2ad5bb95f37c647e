// Robot model files in YAML (models/*.yaml): the edge where text becomes a KinematicModel.
// The format is documented in docs/reference/file-formats.md, "Robot models" and by
// models/reinovo_r1.yaml.
#pragma once

#include <string>

#include "calib/kinematics/kinematic_model.h"

namespace twin {

/// Parses a model from YAML text. `source` names the file in messages. Throws InputError
/// naming the source, the line and the key for malformed YAML, unknown or missing keys, a
/// wrong number of links, non-numeric values and inconsistent values (ValidateModel).
KinematicModel ParseModelYaml(const std::string& text, const std::string& source);

/// Reads and parses a model file; a missing or unreadable file is an InputError naming it.
KinematicModel LoadModelYaml(const std::string& path);

/// Writes a model as YAML text that ParseModelYaml reads back to the same model
/// (angles in degrees, full double precision).
std::string ModelToYaml(const KinematicModel& model);

}  // namespace twin
