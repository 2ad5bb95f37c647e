// The dual-arm workflow (issue 5, item 5): both papers joined on one twin cell.
//   (a) handclasp base-frame calibration (Gan et al. 2014) with the controllers' nominal
//       kinematics (bench/runs/handclasp_run.h);
//   (b) the optical-axis self-calibration of both robots (Zhu et al. 2019), told (a)'s
//       installation-constrained X_B1B2 as its rough base-to-base transform (the paper's b1Tb2
//       of section VI.B), after both robots went back to the scenario's initial joints so that
//       the camera sees the board (bench/runs/calibration_run.h, RunCalibrationStage);
//   (c) the handclasp again, with the identified kinematics as the pendant models (links 1-6
//       and X_BL0 of the identified model, the scenario's tip as tool) and the section's
//       calibrated_operator_error_mm; with calibrated_tip_identification (default) robot 1's
//       tip is taught at 4 orientations per point and both tips are identified on their
//       flanges jointly with X_B1B2 (calib/identification/tip_refinement.h): a single feature point leaves
//       the flange frame's rotation about it unidentified, a constant tip error of about a
//       millimetre for a tip 150 mm off the axis.
// Stage (a) is scored against the link-1 frames of the nominal models (KinematicFrameTruth),
// stage (c) against the best-fit frames of the calibrated models (BestFitBaseOffset: their
// base gauge also holds link 1's beta); the physical transform is reported beside. One
// report.json (and report.html, measurements.csv, servo_*.png, identified_<robot>.yaml) is
// written to a staging folder out_dir + ".partial" and renamed onto out_dir at the end.
// Both handclasp stages teach from the told layout (handclasp.rough_base_from_robot1) with the
// told tips (handclasp.tips); stage (b) is told stage (a)'s estimate as its rough base.
//
// report.json: the calibration keys (scenario, intrinsics, robots, timing_s) plus
//   base_frame.installation
//   base_frame.workflow.{nominal_kinematics,calibrated_kinematics}.{e_tran_mm,e_rot_deg,
//       estimate} (eq. 33-34 of the stage's headline estimate: "tips_identified" when the tip
//       identification succeeded, else "constrained"), .physical_truth, and .stage (the whole
//       handclasp report: general, constrained, tips_identified, scoring_frame, physical_truth,
//       pendant_tip_error, contacts, coupled_motion, ...)
//   base_frame.coupled_motion (stage (c)'s coupled-motion check, issue item 6)
#pragma once

#include "bench/runs/calibration_run.h"

namespace twin {

/// Runs the workflow of a scenario with both a `calibration:` and a `handclasp:` section.
/// Returns 0 when every stage succeeded, 3 when the acceptance criteria are missed. Throws
/// InputError (nothing is written then) for bad input (trials other than 1, a missing
/// section, a bad key), for calibration failures RunCalibrationStage throws and when a
/// handclasp stage refused (naming the scenario, the stage and the reason).
int RunWorkflowScenario(const RunOptions& options);

}  // namespace twin
