// The report of `twinbench run` of a tracker scenario (bench/runs/tracker_run.h): report.json
// and report.html from the run's typed result. Keys of report.json, in this order (nlohmann's
// object sorts them when written):
//   scenario                   the scenario (bench/report/scenario_json.h)
//   procedure, robot           what ran on which robot
//   tracker                    poses, attempts, sigma_mm (the twin's), temperature_reference_C
//                              (null without a temperature sensor), skipped[] {attempt, reason}
//   heldout.<split>            rule, training_poses, before/after point errors, worse
//   truth_position_error_mm    {raw, rigid}.{before, after}.{rms, max}: 200 random
//                              configurations against the true geometry and reflector
//   parameters[]               name, unit, estimated, true, sigma: deviation from nominal
//   declared_term_parameters[] name, unit, estimated, sigma
//   identifiable_combinations  count, within_3_sigma, items[] {index, estimated, true, sigma,
//                              within_3_sigma}
//   unidentifiable, condition_number, sigma0, declared_terms
//   truth_position_error_mm_physical   when the twin reached some of the physical-truth poses:
//                              poses, rule, calibrated_model and (diagnosed) discovered_model,
//                              each {raw, rigid}.{rms, max}; also
//                              truth_position_error_mm_discovered_model (diagnosed)
//   diagnosis                  bench/report/diagnosis_report.h, or {verdict: null, skipped}
//   warnings, timing_s.total, acceptance (bench/report/acceptance.h)
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "bench/io/scenario.h"
#include "bench/report/acceptance.h"
#include "bench/scoring/calibration_scoring.h"
#include "calib/diagnosis/model_discovery.h"
#include "calib/procedures/tracker_procedure.h"

namespace twin {

/// One identifiable combination of the tracker calibration against its true value.
struct TrackerCombinationScore {
  int index = 0;
  double estimated = 0.0, true_value = 0.0, sigma = 0.0;
  bool within_3_sigma = false;
};

/// The scores against the true geometry with the true reflector (bench only).
struct TrackerTruthScores {
  GaugeErrors before, after;       ///< nominal and identified, 200 random configurations [m]
  Eigen::VectorXd phi0, phi_true;  ///< the nominal and the true geometric parameters [SI]
  int within3 = 0;                 ///< identifiable combinations within 3 sigma of the truth
  std::vector<TrackerCombinationScore> combinations;
};

/// The physical truth's errors: the reflector where the twin's physics puts it against the
/// calibrated (and the discovered) model at the same readings [m].
struct TrackerPhysicalTruthScores {
  int poses = 0;                          ///< poses the twin reached; 0: none, no scores
  GaugeErrors calibrated;
  std::optional<GaugeErrors> discovered;  ///< when model discovery ran
};

/// Everything a tracker run's report is made of; the pointers outlive the report's making.
struct TrackerRunResult {
  const Scenario* scenario = nullptr;               ///< as the trial
  std::string robot;                                ///< the robot carrying the reflector
  const TrackerProcedureResult* procedure = nullptr;  ///< points, skips, the calibration
  std::vector<std::string> declared_terms;          ///< the starting model's terms (labels)
  std::vector<std::string> notes;                   ///< DeclaredModel's notes (warnings)
  double tracker_sigma_m = 0.0;                     ///< the twin tracker's noise per axis
  bool truth_available = true;                      ///< false: a cell without truth (`truth`,
                                                    ///< `physical` and tracker_sigma_m unset)
  TrackerTruthScores truth;
  TrackerPhysicalTruthScores physical;
  const DiscoveryResult* diagnosis = nullptr;       ///< model discovery; null when skipped
  std::string diagnosis_skipped;                    ///< why it was skipped
  double total_s = 0.0;                             ///< wall time of the run until the report
};

/// The report's texts and the acceptance verdict evaluated on it.
struct TrackerReport {
  std::string json_text;       ///< report.json (two-space indent, newline)
  std::string html;            ///< report.html
  AcceptanceVerdict verdict;
};

/// The report of `result` with the verdict of `acceptance` (its results in the report).
/// Throws InputError for a criterion naming a figure the report lacks.
TrackerReport MakeTrackerReport(const TrackerRunResult& result, const Acceptance& acceptance);

}  // namespace twin
