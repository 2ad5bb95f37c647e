// How sure an optical-axis identification is: the Gauss-Newton (first-order) covariance of its
// identifiable coordinates z at the solution of IdentifyNonlinear,
//   Cov(x) = s^2 (J^T J)^-1,  s^2 = r^T r / (m - n),
// with x = (z, and per axis the line's 4 degrees of freedom and, with depths, its offset t_k),
// J the Jacobian of the same residuals as the solver's (perpendicular part of p_BE - o - c_k,
// 2 independent rows per sample; the weighted depth residual, 1 row) at the solution, m the
// independent rows and n the unknowns; Cov(z) is its z block (the lines and offsets are
// nuisance parameters, marginalised). A Monte Carlo study checks the claim: the truth should
// lie within 1 and 2 sigma in about 68 % and 95 % of trials (the coverage check of
// bench/report/study_summary.h). Estimator side: residuals and Jacobians only, no truth.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "calib/identification/nonlinear_identification.h"
#include "calib/measurements/optical_axis_model.h"

namespace twin {

/// Outcome of EstimateIdentificationCovariance.
struct IdentificationCovariance {
  bool ok = false;                 ///< false: not estimated (reason says why)
  std::string reason;
  Eigen::MatrixXd z;               ///< rank x rank covariance of z [scaled units^2: m^2, rad^2]
  Eigen::VectorXd sigma_z;         ///< 1-sigma of each coordinate of z [m or rad, scaled]
  /// 1-sigma of each geometric parameter's correction (SI): sqrt(diag(SV Cov(z) (SV)^T));
  /// zero for a parameter that only unidentifiable combinations move (kept at nominal).
  Eigen::VectorXd sigma_parameters;
  double residual_sigma = 0.0;     ///< s, the a-posteriori sigma of a perpendicular row [m]
  int redundancy = 0;              ///< m - n (independent rows less unknowns)
};

/// The covariance of `result` (a successful IdentifyNonlinear on `samples` from `nominal`).
/// Not ok when the identification failed, the problem has no redundancy, or J^T J is singular.
IdentificationCovariance EstimateIdentificationCovariance(
    const KinematicModel& nominal, const std::vector<AxisSample>& samples,
    const NonlinearIdentificationResult& result);

}  // namespace twin
