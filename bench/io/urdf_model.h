// URDF import and export. Import turns a user's URDF (any joint-origin convention) into an
// improved-DH KinematicModel whose forward kinematics equals the URDF's joint chain; export
// writes a KinematicModel as URDF (models/*.urdf are written by `twinbench export-urdf`).
#pragma once

#include <string>
#include <vector>

#include "calib/kinematics/kinematic_model.h"

namespace twin {

/// Options of the URDF import.
struct UrdfImportOptions {
  std::string base_link;  ///< chain start; empty: the URDF's root link
  std::string tip_link;   ///< chain end (becomes the end frame E); empty: the unique leaf
  std::string robot_name; ///< model name; empty: the URDF's robot name
};

/// Builds a model from URDF text. The chain from base_link to tip_link must hold exactly six
/// revolute (or continuous) joints, any number of fixed joints and nothing else. The DH frames
/// follow the joint axes; X_BL0 maps the base link frame to DH frame 0, link 7 is the identity
/// and X_LtE maps it to the tip link frame, so EndPose equals the URDF's tip pose. Masses move
/// to the DH link frames. Throws InputError naming `source`, the joint or link, and what was
/// expected (wrong joint count or type, missing limits, parallel-and-coincident axes, ...).
/// Without tip_link, a URDF with several leaves ends at the one with the most moving joints
/// above it (a frame-only `base` beside `base_link`, as ROS-Industrial URDFs have, is passed
/// over); a tie is an error. `warnings` (optional) receives what a user should know, each
/// naming `source`: that automatic tip choice, mesh files that cannot be resolved (the twin
/// draws capsules), moving links without <inertial> (the stand-in the twin uses).
KinematicModel ParseUrdf(const std::string& text, const std::string& source,
                         const UrdfImportOptions& options = {},
                         std::vector<std::string>* warnings = nullptr);

/// Reads and parses a URDF file; a missing file is an InputError naming it. Mesh paths
/// relative to the file resolve against its folder.
KinematicModel LoadUrdf(const std::string& path, const UrdfImportOptions& options = {},
                        std::vector<std::string>* warnings = nullptr);

/// URDF text of a model: links base_link, link1..link6, tool, end; joints joint1..joint6
/// (revolute, with limits), fixed joints to tool and end; inertials of each link.
std::string ModelToUrdf(const KinematicModel& model);

}  // namespace twin
