// The end point of a robot model and its Jacobian with respect to the model's flat parameters,
// for the identification engine's cost functions. Two ways, tested against each other:
//   - analytic (eq. 5-9, as IdentificationJacobian) when no term sags under gravity or offsets
//     the tool: the geometric columns at the link angles and length scale the terms give, and
//     each term's columns through its joint offsets (the manipulator Jacobian) and its length
//     scale (dp/ds = (p - p_BL0 - R_BLt p_LtE) / s: every other translation scales with s);
//   - forward-mode autodiff (ceres::Jet, kJetStride columns per pass) of RobotEndPoseT
//     otherwise.
// The analytic way is kept for speed (twinbench benchmark-kinematics prints the ratio): the
// pose planner and every identification evaluate it for each measurement at each iteration.
#pragma once

#include <Eigen/Core>

#include "calib/model/robot_model.h"

namespace twin {

/// 3 x n position Jacobian (n = the model's parameters).
using PointJacobian = Eigen::Matrix<double, 3, Eigen::Dynamic>;

/// True when the analytic way applies to `model` (see the header).
bool AnalyticEndPointJacobian(const RobotModel& model);

/// p_BE [m] and d p_BE / d params [m per SI unit] at `params` (flat, ParameterLayout order).
void EndPointJacobian(const RobotModel& model, const double* params,
                      const MeasurementContext& context, Vector3* p, PointJacobian* J);

/// The same by autodiff only (for tests and models with coupled terms).
void EndPointJacobianAutodiff(const RobotModel& model, const double* params,
                              const MeasurementContext& context, Vector3* p, PointJacobian* J);

}  // namespace twin
