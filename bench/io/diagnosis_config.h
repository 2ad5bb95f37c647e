// The `diagnosis:` section of a scenario's procedure (model discovery,
// docs/explanation/discovery-statistics.md), shared by tracker_calibration and calibration (optical
// axes):
//   diagnosis: {enabled: true, alpha: 0.05, min_gain_percent: 5, max_effects: 10, folds: 5,
//               candidates: [joint_compliance:2, ...], truth_poses: 60, screen: true}
// Every key optional; candidates are TYPE[:JOINT[:ORDERS]] (term_spec_text.h), checked against
// the robot's nominal model; truth_poses is the physical-truth scoring's pose count (bench);
// screen: fit every candidate on all the data when the residual is consistent with the noise
// (DiscoveryOptions::screen_when_noise).
// Optical axes also take the stated noise of the diagnosis' floor: perpendicular_sigma_mm
// (the camera's measurement of the servo's residual offset, default 0.02), depth_sigma_mm
// (the depth from the board pose, default 0.1) and encoder_sigma_deg (default 0: not stated).
#pragma once

#include "bench/io/yaml_util.h"
#include "calib/diagnosis/model_discovery.h"
#include "calib/kinematics/kinematic_model.h"

namespace twin {

struct DiagnosisConfig {
  bool enabled = true;
  int truth_poses = 60;
};

/// Reads the section at `field` into `config` and `discovery` (its alpha, min_gain_percent,
/// max_effects, folds, candidates); refuses unknown keys and bad values (ValidateDiscoveryOptions)
/// naming the file, line and key.
/// Adds a told payload (weighed mass [kg], its centre of mass `p_com_L` in the link's frame
/// [m]) to `link`'s inertia as a point mass, so that the gravity terms of the diagnosis see it.
void AddPointMass(double mass_kg, const Vector3& p_com_L, Link* link);

void ParseDiagnosisSection(const YamlReader& reader, const YamlField& field,
                           const KinematicModel& nominal, DiagnosisConfig* config,
                           DiscoveryOptions* discovery, bool optical_axes = false);

}  // namespace twin
