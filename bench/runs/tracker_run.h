// `twinbench run` of a scenario with a `tracker_calibration:` section: the laser-tracker
// procedure (calib/procedures/tracker_procedure.h) on the twin's tracker (`tracker:`), scored
// against the truth (README, "Laser tracker on the twin").
//
// tracker_calibration keys (told values and the procedure's settings; the truth is `tracker:`):
//   robot: r2                        # the robot carrying the reflector
//   told_reflector_mm: [30, -20, 60] # the reflector in the flange frame, by drawing
//   poses: 100                       # measured poses (1..100000)
//   max_attempts: 300                # optional (3 x poses): configurations tried at most
//   joint_margin_deg: 10             # optional: off each joint limit
//   holdout: 0.2                     # optional: the part each held-out split keeps back
#pragma once

#include "bench/runs/calibration_run.h"

namespace twin {

/// The checks `run` makes before it runs (the section, a tracker in the cell, one procedure
/// a scenario); throws InputError naming the scenario and key.
void ValidateTrackerScenario(const Scenario& scenario);

/// Runs it and writes report.json, report.html, measurements.csv (the tracker file format of
/// bench/io/tracker_file.h) and identified_<robot>.yaml. Returns 0, or 3 when acceptance
/// criteria are missed; throws InputError for bad input or a refused procedure.
int RunTrackerScenario(const RunOptions& options);

}  // namespace twin
