// Named kinematic parameters (DESIGN.md, convention 8): the one place that maps names such as
// "r1.link3.alpha" to positions in the flat parameter vector and back.
//
// Flat order: link-major, link 1..7, and within a link theta, d, a, alpha, beta; index =
// 5 * (link - 1) + parameter. (The paper's eq. 9 groups by parameter kind instead; the names
// make the order explicit wherever it matters.)
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "calib/kinematics/kinematic_model.h"

namespace twin {

using ParameterVector = Eigen::Matrix<double, kNumParams, 1>;  ///< SI units (m, rad)

/// Flat index of parameter `which` of link `link` (1-based, 1..7).
int ParameterIndex(int link, DhParameter which);

/// Name of flat index `index` for a robot called `robot`, e.g. "r1.link3.alpha".
std::string ParameterName(const std::string& robot, int index);

/// All 35 names in flat order.
std::vector<std::string> ParameterNames(const std::string& robot);

/// Flat index of a name produced by ParameterName for this robot; throws InputError naming
/// the unknown name and the expected form otherwise.
int FindParameter(const std::string& robot, const std::string& name);

/// True for the length parameters (d, a), false for angles.
bool IsLengthParameter(int index);

/// The model's 35 parameters as a flat vector.
ParameterVector GetParameters(const KinematicModel& model);

/// A copy of `model` whose 35 parameters are `params`.
KinematicModel WithParameters(const KinematicModel& model, const ParameterVector& params);

}  // namespace twin
