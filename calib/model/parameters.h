// Named geometric parameters of a chain (DESIGN.md, convention 8): the one place that maps names
// such as "r1.link3.alpha" to positions in the flat geometric parameter vector and back. The
// full parameter layout of a robot model (geometry plus error terms) builds on it
// (calib/model/parameter_layout.h).
//
// Flat order: link-major, link 1..N+1 (N+1 the tool link), and within a link theta, d, a, alpha,
// beta; index = 5 * (link - 1) + parameter. (The paper's eq. 9 groups by parameter kind
// instead; the names make the order explicit wherever it matters.)
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "calib/kinematics/kinematic_model.h"

namespace twin {

using ParameterVector = Eigen::VectorXd;  ///< SI units (m, rad)

/// Characteristic length [m] dividing the length columns' units: Phi's length columns are
/// multiplied by it so that a metre and a radian weigh about alike for a ~1 m arm (a 1 mrad
/// error moves the tool about 1 mm). Without it the SVD would mix m and rad arbitrarily.
constexpr double kObservabilityCharacteristicLength = 1.0;

/// Flat index of parameter `which` of link `link` (1-based, 1..N+1).
int ParameterIndex(int link, DhParameter which);

/// Name of flat index `index` for a robot called `robot`, e.g. "r1.link3.alpha".
std::string ParameterName(const std::string& robot, int index);

/// All 5 (N + 1) names of `model` in flat order.
std::vector<std::string> ParameterNames(const KinematicModel& model);

/// Flat index of a name produced by ParameterName for this model. Precondition: it is one
/// (no user-given name reaches it); else PreconditionError naming it and the expected form.
int FindParameter(const KinematicModel& model, const std::string& name);

/// True for the length parameters (d, a), false for angles.
bool IsLengthParameter(int index);

/// The model's 5 (N + 1) parameters as a flat vector.
ParameterVector GetParameters(const KinematicModel& model);

/// A copy of `model` whose parameters are `params` (size model.num_parameters()).
KinematicModel WithParameters(const KinematicModel& model, const ParameterVector& params);

}  // namespace twin
