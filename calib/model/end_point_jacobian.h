// The end point of a robot model and its Jacobian with respect to the model's flat parameters,
// for the identification engine's cost functions. Two ways, tested against each other:
//   - analytic (eq. 5-9, as IdentificationJacobian) when no term sags under gravity or offsets
//     the tool: the geometric columns at the link angles and length scale the terms give, and
//     each term's columns through its joint offsets (the manipulator Jacobian) and its length
//     scale (dp/ds = (p - p_BL0 - R_BLt p_LtE) / s: every other translation scales with s);
//   - where terms deflect axes (stage 5) and none sags or offsets the tool: the term columns by
//     autodiff over the term parameters only, the geometric ones analytic on the deflected
//     chain with its deflections held fixed. What that leaves out is the deflections' own
//     change with the geometry (a lever arm's change times a compliance: about |w| ~ 1e-4 of
//     a geometric column), an error in the direction of a Gauss-Newton step, not in the model
//     or its residuals; the term columns are exact (tests/calib/model/terms/
//     deflection_terms_test.cc);
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

/// True when the deflected-chain way applies to `model` (see the header).
bool DeflectedEndPointJacobian(const RobotModel& model);

/// The same by autodiff only (for tests and models with coupled terms).
void EndPointJacobianAutodiff(const RobotModel& model, const double* params,
                              const MeasurementContext& context, Vector3* p, PointJacobian* J);

}  // namespace twin
