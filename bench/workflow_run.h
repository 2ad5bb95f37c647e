// The dual-arm workflow (issue 5, item 5): both papers joined on one twin cell.
//   (a) handclasp base-frame calibration (Gan et al. 2014) with the controllers' nominal
//       kinematics (bench/handclasp_run.h);
//   (b) the optical-axis self-calibration of both robots (Zhu et al. 2019), told (a)'s
//       installation-constrained X_B1B2 as its rough base-to-base transform (the paper's b1Tb2
//       of section VI.B), after both robots went back to the scenario's initial joints so that
//       the camera sees the board (bench/calibration_run.h, RunCalibrationStage);
//   (c) the handclasp again, with the identified kinematics as the pendant models (links 1-6
//       and X_BL0 of the identified model, the scenario's tip as tool) and the section's
//       calibrated_operator_error_mm.
// Both handclasp stages are scored against the frames the kinematic models use (handclasp_run.h,
// KinematicFrameTruth), the physical transform reported beside. One report.json (and
// report.html, measurements.csv, servo_*.png, identified_<robot>.yaml) is written to a staging
// folder out_dir + ".partial" and renamed onto out_dir at the end.
//
// report.json: the calibration keys (scenario, intrinsics, robots, timing_s) plus
//   base_frame.installation
//   base_frame.workflow.{nominal_kinematics,calibrated_kinematics}.{e_tran_mm,e_rot_deg}
//       (the constrained estimate, eq. 33-34), each with .stage (the whole handclasp report:
//       general, constrained, physical_truth, contacts, coupled_motion, ...)
//   base_frame.coupled_motion (stage (c)'s coupled-motion check, issue item 6)
#pragma once

#include "bench/calibration_run.h"

namespace twin {

/// Runs the workflow of a scenario with both a `calibration:` and a `handclasp:` section.
/// Returns 0 when every stage succeeded, 1 when a handclasp stage failed (the report says
/// why). Throws InputError for bad input (trials other than 1, a missing section, a bad key;
/// nothing is written then) and for calibration failures RunCalibrationStage throws.
int RunWorkflowScenario(const RunOptions& options);

}  // namespace twin
