// The MJCF text of a whole twin cell: its arms (TwinSpec::num_robots, one or two) built from
// their true (perturbed) geometry, the hand camera and the chessboard (two-robot cells only),
// the measuring tips, floor and lights.
//
// Names: robot k (k = 1, 2, the scenario's first and second robot) prefixes its elements with
// "robot<k>_". Body frames (calib/common/frames.h letters): the base body "robot<k>_base" sits at
// X_WB; link body "robot<k>_link<i>" (i = 1..6) has the frame U_i = L(i-1) RotZ(theta_offset_i)
// at q = 0, so its hinge "robot<k>_j<i>" is the body's z axis through its origin and qpos is the
// link-side angle q_i. Sites "robot<k>_L<i>" (i = 0..7) are the DH frames L0..L7 and
// "robot<k>_tip" the measuring tip point; they carry the geometry exactly (every number is
// written as its shortest round-trip decimal). The MJCF camera "hand_camera" looks along -z
// with y up; the optical frame C is that frame turned by RotX(pi). Camera housing, board and
// tip are welded child bodies of link 6 ("robot<k>_camera", "robot<k>_board", "robot<k>_tip").
// Contacts: every link, base and tool geom collides with both robots (bodies of one robot only
// when not adjacent); a tip collides with the other robot only, never with the other tip
// (handclasp contacts). Excluded pairs: base-link1 (MuJoCo's parent filter skips static
// bodies) and links i, i+2 when link i+1 is shorter than their radii (the spherical wrist).
// The floor is visual only. Joint damping is CriticalDamping(kp, M_ii) with M_ii the joint's
// composite inertia plus armature at the robot's initial pose.
#pragma once

#include <array>
#include <string>

#include "calib/kinematics/kinematic_model.h"
#include "sim/effects/effect.h"
#include "sim/world/twin_spec.h"

namespace twin {

/// Name of the MJCF camera on the active robot's flange.
constexpr const char* kHandCameraName = "hand_camera";

/// Stand-in mass properties of a link whose model has no mass (a URDF without <inertial>):
/// MuJoCo needs every body to have mass. [kg], [kg m^2] about each axis at the link origin.
constexpr double kFallbackLinkMassKg = 0.1;
constexpr double kFallbackLinkInertiaKgm2 = 1e-4;

/// Radius of the flange disc (and of the last link's capsule) of an n-joint arm [m]; the disc
/// is kFlangeThicknessM thick, behind the flange face (frame L_N) [m].
double FlangeRadius(int num_joints);
constexpr double kFlangeThicknessM = 0.012;

/// Joint damping [N m s/rad] for near-critical damping of a position servo of stiffness `kp`
/// [N m/rad] on a joint of effective inertia `inertia` [kg m^2]: 2 sqrt(kp * inertia).
double CriticalDamping(double kp, double inertia);

/// The whole cell as MJCF text; only the first spec.num_robots entries of the arrays are read.
/// `true_models` replace spec.robots[k].model (they carry the
/// geometry effects); `drives` give each joint's position-actuator gain kp [N m/rad]; `mounts`
/// the compliance of each robot's target bracket: a compliant board hangs on three slide
/// joints "robot<k>_mount_x/y/z" along the flange axes, springs of stiffness m g / d;
/// `structures` the elastic supports of each robot: a compliant joint i's body hangs on two
/// spring hinges "robot<k>_j<i>_tilt_x/y" about its body frame's x and y axes, before the joint
/// (so fixed in the parent), a compliant base on "robot<k>_base_tilt_x/y" about the base frame's
/// x and y axes at its origin.
std::string WriteTwinMjcf(const TwinSpec& spec, const std::array<KinematicModel, 2>& true_models,
                          const std::array<std::vector<JointDrive>, 2>& drives,
                          const std::array<MountCompliance, 2>& mounts = {},
                          const std::array<StructureCompliance, 2>& structures = {});

/// Largest omega * timestep of a mount's spring (armature is added to stay below it): the
/// explicit stiffness step of MuJoCo's Euler integrator is well inside its stability limit.
constexpr double kMaxMountOmegaDt = 1.0;

/// Largest omega * timestep of a tilt hinge's spring on its armature alone (the bodies'
/// inertia only lowers it), for the same reason.
constexpr double kMaxTiltOmegaDt = 1.0;

}  // namespace twin
