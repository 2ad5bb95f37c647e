// `twinbench new-scenario`: a valid, commented scenario file for any six-axis arm (issue 41,
// part 4). From the arm's model alone it derives the cell the shipped scenarios were set up
// by hand (scenarios/paper_reinovo.yaml, abb_irb2400.yaml, kuka_kr6r900.yaml,
// tracker_reinovo.yaml, gan2014_*.yaml):
//   - the reach R (largest horizontal distance of the flange from the base axis over random
//     joint angles inside the limits) and the shoulder height;
//   - two bases facing each other on the floor, D apart, with the camera on robot 1's flange
//     and the board on robot 2's facing each other at the working distance w between them;
//     D, the heights and the initial joints come from a small search over where the two meet
//     (a fraction of R out, a few heights), each candidate solved by the estimator's IK
//     (calib/kinematics/inverse_kinematics.h, as `twinbench ik`) and scored by the smaller
//     manipulability of the two arms and their distance from the joint limits; the best one
//     whose cell settles without a collision (the twin, as `twinbench check`) is written;
//   - for the handclasp, D instead from where its cube is reachable: a search over D with the
//     run's planner (bench/runs/handclasp_run.h, TeachHandclaspPoints) from the joints'
//     mid-range (the file's initial joints), the best candidates tried on the twin until one
//     makes a contact at every taught point;
//   - the planning region (the camera search box) round robot 1's start pose;
//   - the told values (rough base, rough hand-eye, the reflector or the tips by drawing) off
//     the truth by the amounts of the shipped scenarios, stated in the file's comments.
// A tracker scenario without --second is one arm alone (scenarios/tracker_single_reinovo.yaml):
// no camera, board or second robot; its start pose puts the flange face out along the base's x
// at 0.5..0.7 of the reach (BestPose, as robot 1's camera above), the tracker max(2 m, 2 R)
// behind the base.
// The file is checked as `twinbench check` checks it before it appears: it is written to a
// temporary file beside --out, validated, and linked into place only if --out still does not
// exist (an existing file is never replaced).
#pragma once

#include <string>

#include "bench/io/model_loader.h"
#include "calib/kinematics/kinematic_model.h"

namespace twin {

/// Options of RunNewScenario (the verb's command line).
struct NewScenarioOptions {
  std::string robot;      ///< robot 1's model (.yaml/.yml/.urdf): the camera robot
  std::string second;     ///< robot 2's model (empty: the same as robot; for the tracker, a
                          ///< one-robot cell)
  ModelLinks links;       ///< URDF chain of robot (and of second when that is empty)
  ModelLinks second_links;  ///< URDF chain of second
  std::string procedure;  ///< optical-axis | tracker | handclasp
  std::string out;        ///< the scenario file to write (must not exist)
};

/// Which way the flange face points in the model's flange frame L_N (the frame hand-eye and
/// board mount are given in): RotX(180 deg) where L_N's z points into the wrist (KUKA's A6),
/// identity where it points out. Decided by the end frame's z where it is (anti)parallel to
/// L_N's (a URDF's tool0, ROS-Industrial: z out of the flange), else by the sign of the
/// flange link's d, the parser's rule for default tips (bench/io/scenario.h).
Transform FlangeOutFrame(const KinematicModel& model);

/// The model with its end frame on the flange frame L_N (tool link and X_LtE identity).
KinematicModel FlangeOnlyModel(const KinematicModel& model);

/// The reach R [m]: the largest horizontal distance of the flange from the base's z axis over
/// `samples` seeded random joint angles inside the limits.
double HorizontalReach(const KinematicModel& model, int samples = 4000);

/// The scenario text for `options` (nothing written). Throws InputError for bad input (an
/// unknown procedure, a model that cannot be loaded, an arm no cell could be found for).
std::string NewScenarioText(const NewScenarioOptions& options);

/// The verb: refuses an existing --out (InputError, exit 2), writes NewScenarioText's file
/// atomically, prints what it wrote; returns 0.
int RunNewScenario(const NewScenarioOptions& options);

}  // namespace twin
