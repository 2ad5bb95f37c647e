// Joint refinement of the base-to-base transform and both measuring-tip offsets from handclasp
// contacts: an extension of Gan, Dai, Dong 2014, whose eq. 3 and 12 take each tip's position on
// its flange as known. After a kinematic calibration that sees a single feature point (Zhu et
// al. 2019), the flange frame of the identified model is only known up to a constant rotation
// about that point (the unidentifiable link-6 / tool combinations), so a tip 150 mm from the
// flange axis carries a constant error of a millimetre in the model's flange frame: the TCP
// must be re-identified with the calibrated kinematics, as a pendant's TCP calibration does.
//
// Model: at contact i the two tips touch,
//   X_B1F1_i (t1 + dt1) = X_B1B2 X_B2F2_i (t2 + dt2),
// X_BF the flange poses from the controllers' models, t the nominal tip points in the flange
// frames, dt their corrections. One direction is never observable: at a handclasp the tips face
// each other along a common axis, so lengthening tip 1 along its axis and shortening tip 2 by
// the same amount moves both contact points together and leaves every equation satisfied. The
// gauge is fixed by keeping dt1 perpendicular to tip 1's axis; X_B1B2 does not depend on it.
// The rest is observable only if the tip orientations vary between contacts (a constant
// orientation makes dt a constant shift, indistinguishable from the translation of X_B1B2), and
// the two flanges' relative orientation too (the roll of robot 2's tip about the common axis:
// with it fixed, only dt1 - R dt2 is seen): the solver checks the conditioning and refuses
// otherwise.
#pragma once

#include <string>
#include <vector>

#include "calib/kinematics/kinematic_model.h"

namespace twin {

/// Options of RefineBaseAndTips.
struct TipRefinementOptions {
  /// Refuse when the smallest singular value of the column-scaled Jacobian, relative to the
  /// largest, is below this (the tip orientations vary too little).
  double min_relative_singular_value = 1e-3;
  /// Length that scales the rotation columns of the Jacobian [m] (about the contact spread).
  double rotation_scale_m = 0.5;
  int max_iterations = 50;

  /// Throws PreconditionError naming the bad field and its value (no user sets these).
  void Validate() const;
};

/// Result of RefineBaseAndTips.
struct TipRefinementResult {
  bool ok = false;
  std::string reason;                              ///< why not ok
  Transform X_B1B2 = Transform::Identity();        ///< refined base-to-base transform
  Vector3 dt1_F1 = Vector3::Zero();                ///< tip 1 correction in flange 1 [m]
  Vector3 dt2_F2 = Vector3::Zero();                ///< tip 2 correction in flange 2 [m]
  Vector3 sigma_dt1_F1 = Vector3::Zero();          ///< 1-sigma of dt1 (from the residuals) [m]
  Vector3 sigma_dt2_F2 = Vector3::Zero();          ///< 1-sigma of dt2 [m]
  double rms_residual_m = 0.0;                     ///< RMS contact mismatch after [m]
  double rms_residual_before_m = 0.0;              ///< with the nominal tips and the initial X
  double relative_singular_value = 0.0;            ///< conditioning (see options)
  int iterations = 0;
};

/// Refines X_B1B2 (from `X_B1B2_initial`, e.g. the general solution of eq. 3 and 12) and the
/// tip corrections from the flange poses at the contacts. Needs at least 4 contacts (11
/// unknowns, 3 equations each). Throws PreconditionError for mismatched or non-finite input
/// (forward kinematics and validated models: never a user's numbers) and bad options; returns
/// ok = false with a reason when the problem is ill-conditioned.
TipRefinementResult RefineBaseAndTips(const std::vector<Transform>& X_B1F1,
                                      const std::vector<Transform>& X_B2F2,
                                      const Vector3& t1_F1, const Vector3& t2_F2,
                                      const Vector3& tip1_axis_F1,
                                      const Transform& X_B1B2_initial,
                                      const TipRefinementOptions& options = {});

}  // namespace twin
