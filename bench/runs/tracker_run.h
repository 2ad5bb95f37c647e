// `twinbench run` of a scenario with a `tracker_calibration:` section: the laser-tracker
// procedure (calib/procedures/tracker_procedure.h) on the twin's tracker (`tracker:`), scored
// against the truth (docs/explanation/methods.md, "Laser tracker on the twin").
//
// tracker_calibration keys (told values and the procedure's settings; the truth is `tracker:`):
//   robot: r2                        # the robot carrying the reflector
//   told_reflector_mm: [30, -20, 60] # the reflector in the flange frame, by drawing
//   poses: 100                       # measured poses (1..100000)
//   max_attempts: 300                # optional (3 x poses): configurations tried at most
//   joint_margin_deg: 10             # optional: off each joint limit
//   holdout: 0.2                     # optional: the part each held-out split keeps back
//   tracker_sigma_mm: 0.01           # optional (0.01): the tracker's datasheet sigma per axis
//   encoder_sigma_deg: 0.0006        # optional (0): the encoders' datasheet noise, for the
//                                    # diagnosis's noise floor
//   payload: {mass_kg: 0.2, xyz_mm: [0, 0, 40]}  # optional (none): what the flange carries
//                                    # besides the reflector, as weighed and drawn (its centre
//                                    # of mass in the flange frame), for the gravity terms
//   diagnosis:                       # optional: model discovery (calib/diagnosis/)
//     enabled: true                  #   false: skip it (as --no-diagnosis)
//     alpha: 0.05                    #   level of the residual test and of each step
//     min_gain_percent: 5            #   smallest held-out gain worth a term
//     max_effects: 10
//     folds: 5
//     candidates: [joint_compliance:2, transmission_error:1:1]  # default: every term
//     truth_poses: 60                #   poses of the physical-truth scoring (bench)
// Effects of the twin with declared: true and a term in the estimator's library
// (joint_compliance, transmission_error, backlash, mount_deflection) are in the estimator's
// model from the start, by type and joint only.
#pragma once

#include "bench/runs/calibration_run.h"

namespace twin {

/// The checks `run` makes before it runs (the section, a tracker in the cell, one procedure
/// a scenario); throws InputError naming the scenario and key.
/// `served_cell`: the run drives a served cell (--cell), whose tracker is the cell's own: the
/// scenario's `tracker:` section (the twin's truth) may then be absent.
void ValidateTrackerScenario(const Scenario& scenario, bool served_cell = false);

/// Runs it and writes report.json, report.html, measurements.csv (the tracker file format of
/// bench/io/tracker_file.h) and identified_<robot>.yaml. Returns 0, or 3 when acceptance
/// criteria are missed; throws InputError for bad input or a refused procedure.
int RunTrackerScenario(const RunOptions& options);

}  // namespace twin
