// Effects on the truth side of the twin. An effect changes what the twin does, never what the
// estimator is told. Each effect is one class in sim/effects/ plus one line in the registry
// (sim/effects/registry.cc); it checks its own parameters. Hooks that an effect does not need
// keep their do-nothing defaults.
#pragma once

#include <memory>
#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "calib/kinematics/kinematic_model.h"
#include "sim/world/twin_spec.h"

namespace twin {

/// Per-joint drive settings an effect may change.
struct JointDrive {
  double stiffness = 0.0;          ///< position-actuator kp [N m/rad]
  bool gravity_feedforward = true; ///< false: the link sags by gravity torque / stiffness
};

/// Compliance of the bracket that holds a robot's mounted target (the chessboard) on its
/// flange: the static deflection of the target under 1 g along each flange axis [m]. Zero: rigid.
struct MountCompliance {
  Vector3 deflection_F = Vector3::Zero();  ///< along x_F, y_F, z_F [m]
  bool any() const { return deflection_F.cwiseAbs().maxCoeff() > 0.0; }
};

/// Elastic supports of a robot's structure, simulated physically as passive hinges with
/// springs that gravity bends. Zero stiffness: rigid (no hinge).
struct StructureCompliance {
  /// Per joint: tilting stiffness of its bearing about the two axes perpendicular to its axis
  /// (x and y of the joint's body frame, fixed in the parent link), at the joint's anchor
  /// [N m/rad]; empty or 0: rigid.
  std::vector<double> joint_tilt_stiffness;
  /// Tilting stiffness of the base's mounting about the base frame's x and y axes, at the
  /// base origin [N m/rad]; 0: rigid.
  double base_tilt_stiffness = 0.0;
};

class Effect {
 public:
  virtual ~Effect() = default;
  /// The spec it was made from (type, declared, robot, joint, params).
  virtual const EffectSpec& spec() const = 0;
  /// Static change of robot `robot`'s true geometry, before the world is built.
  virtual void ApplyToGeometry(int robot, KinematicModel* model, std::mt19937_64* rng) const;
  /// True if this effect changes robot `robot`'s link lengths over time (LengthScaleAt).
  virtual bool DriftsLengths(int robot) const;
  /// Factor on d and a of every link of robot `robot`'s true geometry at the twin's time
  /// `time_s` [s], on top of the static geometry (1 at time 0 and for effects that do not
  /// drift). The twin moves its bodies accordingly as its clock runs.
  virtual double LengthScaleAt(int robot, double time_s) const;
  /// Robot `robot`'s temperature above the cold start at the twin's time `time_s` [K] (what
  /// its structure's temperature sensor sees, when it has one); 0 for effects that do not warm
  /// the arm.
  virtual double TemperatureDeltaAt(int robot, double time_s) const;
  /// Compliance of the target mount on robot `robot`'s flange.
  virtual void ApplyToMount(int robot, MountCompliance* mount) const;
  /// Drive settings of robot `robot`'s joints.
  virtual void ApplyToDrive(int robot, std::vector<JointDrive>* drives) const;
  /// Elastic supports of robot `robot`'s structure (joint bearings, base).
  virtual void ApplyToStructure(int robot, StructureCompliance* structure) const;
  /// True if this effect tilts robot `robot`'s joint axes with their angles (AddAxisTilt).
  virtual bool TiltsAxes(int robot) const;
  /// Adds to `tilt` the kinematic tilt of each joint axis of robot `robot` at link-side angles
  /// `q_link` [rad]: the x and y components of the small rotation, in the parent's DH frame
  /// L(i-1) of joint i and about its origin, applied before the joint's own rotation [rad].
  virtual void AddAxisTilt(int robot, const JointVector& q_link,
                           std::vector<Eigen::Vector2d>* tilt) const;
  /// Adds to `link_offset` the link-side minus motor-side angle of each joint for motor angles
  /// `motor`, approached moving in `direction` (+1, -1 per joint; 0 if never moved) [rad].
  virtual void ApplyToTransmission(int robot, const JointVector& motor,
                                   const JointVector& direction, JointVector* link_offset) const;
  /// Changes the encoder reading (motor side) of robot `robot` [rad].
  virtual void ApplyToEncoder(int robot, JointVector* reading, std::mt19937_64* rng) const;
  /// Changes a rendered camera image (8-bit BGR).
  virtual void ApplyToImage(cv::Mat* image, std::mt19937_64* rng) const;
  /// True if this effect acts only through the hand camera or the board (the image, the
  /// target's bracket): it has nothing to act on in a cell without them.
  virtual bool NeedsCameraAndBoard() const;

 protected:
  /// True if this effect acts on `robot` / `joint` (its spec's -1 means all).
  bool Applies(int robot) const;
  bool Applies(int robot, int joint) const;
};

/// Builds the effect named by spec.type; throws InputError naming spec.where for an unknown
/// type (listing the known ones), an unknown or missing parameter, or a bad value.
std::unique_ptr<Effect> MakeEffect(const EffectSpec& spec);

/// Every effect of `spec` (MakeEffect), in order; also throws InputError naming the effect's
/// where for one that needs the camera and the board (Effect::NeedsCameraAndBoard) in a cell
/// without them (TwinSpec::HasCameraAndBoard).
std::vector<std::unique_ptr<Effect>> MakeEffects(const TwinSpec& spec);

/// Names of the registered effect types.
std::vector<std::string> EffectTypes();

}  // namespace twin
