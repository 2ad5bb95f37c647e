// Base-frame calibration between two cooperating robots from "handclasp" contacts, after
// Gan, Dai, Dong, "Robot Calibration for Cooperative Process under Typical Installation" (2014).
//
// Each contact i is one physical point measured by both robots' kinematics: p_B1[i] in robot 1's
// base frame B1 and p_B2[i] in robot 2's base frame B2, so p_B1[i] = X_B1B2 * p_B2[i].
// Steps (paper section 2): a general linear solution from N >= 4 pairs, its Frobenius-nearest
// rotation (eq. 3), the installation refinement of the preliminary rotation (floor-floor
// eq. 4-11, floor-wall eq. 13-21, floor-ceiling eq. 22-30), and the translation (eq. 12).
// Accuracy is scored as in section 4: e_tran (eq. 34) and e_rot on ZYZ Euler angles (eq. 31-33).
//
// Error policy: malformed input (p_B1 and p_B2 of different lengths, non-finite coordinates,
// invalid options) is a caller's bug (the contacts are forward kinematics of encoder readings,
// no user sets the options) and throws PreconditionError; well-formed input that cannot give
// a calibration (fewer than 4 contacts, a degenerate contact set) or a solver failure is
// reported by the result's status and reason, so that a procedure can ask the operator to
// teach more or better points.
#pragma once

#include <string>
#include <vector>

#include "calib/common/frames.h"

namespace twin {

/// How robot 2's base is installed relative to floor-mounted robot 1 (paper section 2.1).
/// Named BaseConstraint to stay distinct from sim/'s twin::Installation.
enum class BaseConstraint {
  kFloorFloor,    ///< z_B2 parallel to z_B1: R_B1B2 = Rot(Z, theta) (eq. 4)
  kFloorWall,     ///< z_B2 perpendicular to z_B1: R = Rot(Z,beta) Rot(Y,-90deg) Rot(Z,alpha) (eq. 16)
  kFloorCeiling,  ///< z_B2 antiparallel to z_B1: R = Rot(Z, theta) Rot(X, 180deg) (eq. 24)
  kGeneral,       ///< no installation constraint: the constrained result equals the general one
};

/// Name of a constraint for messages and reports, e.g. "floor-wall".
const char* ToString(BaseConstraint constraint);

/// Tuning of CalibrateBaseFrame. Ratios are of singular values of the centred contact cloud.
struct BaseCalibrationOptions {
  /// Refuse as collinear when sigma2 / sigma1 of the centred cloud is below this (unitless).
  double collinear_ratio_min = 1e-3;
  /// Refuse as coplanar when sigma3 / sigma1 of the centred cloud is below this (unitless); the
  /// general solution's rotation error grows like contact error / (sigma3 scale).
  double coplanar_ratio_min = 1e-3;
  /// Side length of the paper's recommended triangular pyramid of contacts [m] (section 3).
  double recommended_side_m = 1.0;
  /// Warn when the largest distance between contacts is below this fraction of
  /// recommended_side_m (unitless, in (0, 1]).
  double side_warn_fraction = 0.5;
  /// Warn (pyramid too flat or too thin) when sigma3 / sigma1 is below this (unitless; a
  /// regular tetrahedron has 1).
  double flatness_warn_ratio = 0.2;
  /// Warn when the constrained rotation is further than this from the general one [rad]: the
  /// declared installation probably does not hold.
  double installation_mismatch_warn_rad = DegToRad(2.0);
  /// Levenberg-Marquardt (Ceres) iteration limit for the floor-wall refinement (eq. 21).
  int lm_max_iterations = 100;
  /// Ceres function tolerance for the floor-wall refinement (relative cost change).
  double lm_function_tolerance = 1e-14;
  /// Ceres parameter tolerance for the floor-wall refinement (relative step).
  double lm_parameter_tolerance = 1e-12;

  /// Throws PreconditionError naming the bad field and its value (no user sets these).
  void Validate() const;
};

/// Outcome of CalibrateBaseFrame.
struct BaseCalibrationResult {
  enum class Status {
    kSuccess,       ///< both transforms are valid
    kTooFewPoints,  ///< fewer than 4 contacts; no transform computed
    kDegenerate,    ///< contacts (nearly) collinear or coplanar; no transform computed
    kNotConverged,  ///< X_B1B2_general valid; the floor-wall LM did not converge
  };
  Status status = Status::kTooFewPoints;
  std::string reason;                 ///< why the status is not kSuccess (empty on success)
  std::vector<std::string> warnings;  ///< advice on contact geometry or installation mismatch
  /// General solution: linear fit, rotation orthonormalized by eq. 3, translation by eq. 12.
  Transform X_B1B2_general = Transform::Identity();
  /// Installation-refined solution: eq. 11, 17 or 30 then eq. 12 (equals general for kGeneral).
  Transform X_B1B2_constrained = Transform::Identity();
  double rms_residual_general_m = 0.0;      ///< RMS of |p_B1 - X_general p_B2| [m]
  double rms_residual_constrained_m = 0.0;  ///< RMS of |p_B1 - X_constrained p_B2| [m]
  Vector3 singular_values_m = Vector3::Zero();  ///< of the centred p_B2 cloud, descending [m]

  bool ok() const { return status == Status::kSuccess; }
};

/// Name of a status, e.g. "kDegenerate".
const char* ToString(BaseCalibrationResult::Status status);

/// Estimates X_B1B2 from contacts p_B1[i] = X_B1B2 p_B2[i] (metres) under `constraint`.
/// Throws PreconditionError if the vectors differ in length, hold non-finite values or options
/// are bad.
BaseCalibrationResult CalibrateBaseFrame(const std::vector<Vector3>& p_B1,
                                         const std::vector<Vector3>& p_B2,
                                         BaseConstraint constraint,
                                         const BaseCalibrationOptions& options = {});

/// The rotation nearest in Frobenius norm to M with det +1 (eq. 3), via SVD.
Matrix3 NearestRotation(const Matrix3& M);

/// Rot(Z, phi) Rot(Y, theta) Rot(Z, psi) for zyz = (phi, theta, psi) [rad] (eq. 31).
Matrix3 RotationFromZyz(const Vector3& zyz);

/// ZYZ Euler angles (phi, theta, psi) [rad] of a rotation by eq. 32, theta in [0, pi] and
/// phi, psi in (-pi, pi]. Where theta is within degenerate_tol_rad of 0 or pi only phi + psi
/// (theta ~ 0) or psi - phi (theta ~ pi) is defined: as the paper does, phi := 0, then eq. 32
/// gives theta = atan2(a_x, a_z) (signed, near 0 or +-pi) and psi = atan2(n_y, o_y).
Vector3 ZyzFromRotation(const Matrix3& R, double degenerate_tol_rad = 1e-12);

/// Calibration errors of section 4 in report units.
struct BaseFrameError {
  double e_tran_mm = 0.0;  ///< infinity norm of the translation difference [mm] (eq. 34)
  double e_rot_deg = 0.0;  ///< infinity norm of the ZYZ Euler-angle difference [deg] (eq. 33)
};

/// Scores an estimated X_B1B2 against the truth by eq. 33-34. Angle differences are wrapped to
/// (-180, 180] deg. If either rotation's middle ZYZ angle is within zyz_degenerate_rad of 0 or
/// 180 deg, both are decomposed with the paper's degenerate convention (phi := 0, see
/// ZyzFromRotation), so that the undefined phi/psi split does not count as error.
BaseFrameError CompareBaseFrames(const Transform& estimate, const Transform& truth,
                                 double zyz_degenerate_rad = DegToRad(1.0));

}  // namespace twin
