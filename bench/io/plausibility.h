// Plausibility limits of the robot-model inputs (YAML models and URDFs), each with its reason.
// A value outside them is finite but absurd (a 1000 km link, a 1e308 kg mass): the run would
// go on and produce numbers that mean nothing, or never end. The model readers refuse it with
// exit code 2, naming the file, line and key and the limit. The limits of the cell and of the
// procedures sit next to their own checks: sim/world/twin_spec.cc (camera, board, tips,
// physics), sim/effects/*.cc (effects), bench/io/scenario.cc (told values, acceptance),
// bench/io/calibration_config.cc and bench/runs/handclasp_run.cc (procedure options),
// bench/runs/calibration_run.cc (measurement files) and bench/twinbench_main.cc (options).
#pragma once

#include <optional>
#include <string>

#include "calib/common/frames.h"

namespace twin::plausibility {

/// Largest |d|, |a| of a link, |xyz| of a fixed base/end transform or URDF joint origin, and
/// the largest centre-of-mass offset [m]. The largest industrial arms reach about 4 m; a
/// 10 m link is almost always millimetres read as metres.
constexpr double kMaxLinkLengthM = 10.0;
/// Largest |theta_offset|, |alpha|, |beta| and rpy angle [rad]: one full turn. Angles are
/// periodic; a larger value is almost always degrees written into a file whose angle_unit is
/// rad.
constexpr double kMaxAngleRad = 2.0 * kPi;
/// Largest |lower|, |upper| joint limit [rad]: two turns each way (multi-turn wrist joints
/// exist; continuous URDF joints are given +-one turn).
constexpr double kMaxJointTravelRad = 4.0 * kPi;
/// Largest mass of one link [kg]: the links of the heaviest industrial robots (2.3 t payload)
/// weigh about a tonne; 10^4 kg leaves a factor of ten. Masses must be >= 0 and not NaN.
constexpr double kMaxLinkMassKg = 1.0e4;

/// Each returns what is wrong with the value (naming the limit and its reason), or nullopt.
/// `unit` is how the value is written in the file ("m", "deg", "rad"), `scale` the factor from
/// that unit to SI.
std::optional<std::string> LengthProblem(double value_m);
std::optional<std::string> AngleProblem(double value_rad, const std::string& unit, double scale);
std::optional<std::string> JointLimitProblem(double value_rad, const std::string& unit,
                                             double scale);
std::optional<std::string> MassProblem(double mass_kg);
/// An inertia tensor about the centre of mass [kg m^2] for a body of `mass_kg`: finite,
/// symmetric, principal moments >= 0 (> 0 with mass) satisfying the triangle inequality
/// (I1 + I2 >= I3: no body has a moment larger than the sum of the other two), zero without
/// mass, and no principal moment above mass * kMaxLinkLengthM^2 (the body would have to
/// reach beyond 10 m).
std::optional<std::string> InertiaProblem(double mass_kg, const Matrix3& I_com);

}  // namespace twin::plausibility
