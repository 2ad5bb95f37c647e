// Closed-form inverse kinematics of a six-joint arm with a spherical wrist (issue 42): the
// last three joint axes meet in one point (the wrist centre), joints 2 and 3 are parallel and
// joint 1 is not parallel to joint 2, the structure of most industrial six-axis arms (the
// Reinovo, KUKA and ABB models of models/; not the Motoman, whose axes 5 and 6 are 30 mm
// apart). It gives every solution at once (up to 8: shoulder front/back, elbow up/down, wrist
// flipped or not) with no iterations, where the iterative solver (inverse_kinematics.h) needs
// tens of damped steps a start.
//
// Method: the product of exponentials of the chain at q = 0 (the joint axes as lines in B from
// the model's own forward kinematics, so every DH form, theta offset, Hayati beta and base or
// tool transform is taken as it is), X_BE(q) = e^(xi_1 q_1) ... e^(xi_6 q_6) X_BE(0), solved by
// the Paden-Kahan subproblems (Murray, Li and Sastry, "A Mathematical Introduction to Robotic
// Manipulation", 1994, section 3.2):
//   1. the wrist centre w (fixed by joints 4-6) must reach X_target X_BE(0)^-1 w: joint 1 from
//      the one condition that joints 2 and 3 cannot change, the offset of w along their common
//      axis direction (a cos q1 + b sin q1 = c, two solutions);
//   2. joint 3 from the distance of w to a point of axis 2 (subproblem 3, two solutions),
//      joint 2 by turning w onto the target about axis 2 (subproblem 1);
//   3. joints 4 and 5 by turning axis 6's direction onto its target (subproblem 2, two
//      solutions), joint 6 by turning a vector across axis 6 (subproblem 1).
// The structure is checked on the model as given: a calibrated model whose axes are a few
// micrometres off the ideal has no exact closed form, and SolveIkSphericalWrist then answers
// with the iterative solver (the fallback).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "calib/kinematics/inverse_kinematics.h"
#include "calib/kinematics/kinematic_model.h"

namespace twin {

/// The closed form of one model, prepared once (the axes at q = 0) and solved per target.
class SphericalWristIk {
 public:
  /// The solver of `model`, or nullopt with the reason in *why (the joint count, the axes that
  /// are not parallel, the wrist axes that miss each other by how much) when the model lacks the
  /// structure to within `tolerance` (metres for points on lines, radians for directions).
  static std::optional<SphericalWristIk> For(const KinematicModel& model, std::string* why,
                                             double tolerance = 1e-9);

  /// Every joint vector (each angle in (-pi, pi], limits not applied) whose end pose is
  /// X_BE_target to within 1e-9 m and 1e-9 rad, checked by forward kinematics; empty when the
  /// target is out of reach, or when the wrist centre is on axis 1 (every joint-1 angle
  /// would do: no closed-form answer). Joint 5 straight gives one wrist answer of the family
  /// (joints 4 and 6 then turn the same axis), the elbow stretched one elbow answer; within
  /// about 1e-7 rad of those singularities the answers off them may be missing.
  std::vector<JointVector> Solve(const Transform& X_BE_target) const;

  /// Solve's answers that fit the limits, each joint turned by whole turns to its angle inside
  /// the limits nearest q_seed's, nearest q_seed first (joint-space distance). q_seed: one
  /// finite angle per joint.
  std::vector<JointVector> InsideLimits(const Transform& X_BE_target,
                                        const JointVector& q_seed) const;

  /// Whether Nearest answers in closed form for these: orientation counted, tolerances at
  /// least its 1e-9, and q_seed a finite vector inside the limits.
  bool Serves(const JointVector& q_seed, const IkOptions& options) const;

  /// The first of InsideLimits (the answer nearest q_seed), with iterations 0 and starts 1.
  /// SolveIk on the model where the closed form does not serve (Serves is false) or has no
  /// answer inside the limits.
  IkResult Nearest(const Transform& X_BE_target, const JointVector& q_seed,
                   const IkOptions& options = {}) const;

 private:
  explicit SphericalWristIk(const KinematicModel& model) : model_(model) {}
  KinematicModel model_;
  Vector3 w_[6];           // joint axes' directions in B at q = 0 (unit)
  Vector3 r_[6];           // a point of each axis in B at q = 0
  Vector3 wrist_centre_;   // where axes 4, 5 and 6 meet, in B at q = 0
  Transform X_BE0_;        // end pose at q = 0
};

/// SolveIk with the closed form where `model` has a spherical wrist: SphericalWristIk::For
/// then Nearest, and SolveIk itself without the structure. It prepares the closed form (one
/// forward kinematics) on every call; a caller solving many targets of one model keeps a
/// SphericalWristIk (the pose planner does).
IkResult SolveIkSphericalWrist(const KinematicModel& model, const Transform& X_BE_target,
                               const JointVector& q_seed, const IkOptions& options = {});

}  // namespace twin
