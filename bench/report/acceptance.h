// CI verdicts: a scenario's optional `acceptance:` section, a list of criteria on report.json
// figures that `twinbench run` checks after the run, and the JUnit XML report of them.
//
//   acceptance:
//     - {figure: robots.r2.truth_position_error_mm.rigid.after.rms, max: 0.3}
//     - {figure: robots.r2.misaligned_error_mm.validation.decrease_percent, min: 95}
//     - {figure: base_frame.workflow.calibrated_kinematics.e_tran_mm, max: 1.0,
//        name: workflow base transform}          # optional test-case name
//
// `figure` is a key path into report.json: keys joined by '.', array items by .i or [i]
// (robots.r2.servo.failures.0.frames; inside a {...} flow map YAML reads '[' as a list, so
// write .i there or quote the path); `max` and/or `min` (at least one) bound it, inclusive.
// Before the run the section is checked (types, a known top-level key such as robots,
// intrinsics, base_frame, timing_s, scenario; robots.<name> naming a robot of the scenario); a
// path that does not resolve in the finished report, or resolves to something other than a
// number, is bad input too (exit 2, nothing written). A figure that is null in the report (not
// computed) fails its criterion. `twinbench run` exits 3 when a criterion fails, printing which
// and by how much; report.json gets an `acceptance` list of the results; `--junit FILE` writes
// one JUnit test case per criterion (a single passing case "run" without criteria).
#pragma once

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/io/scenario.h"

namespace twin {

/// The exit code of a run that ran but missed its acceptance criteria.
constexpr int kExitAcceptanceFailed = 3;

/// One criterion as written.
struct AcceptanceCriterion {
  std::string figure;           ///< key path into report.json
  std::optional<double> max;    ///< figure <= max
  std::optional<double> min;    ///< figure >= min
  std::string name;             ///< test-case name (default: the figure and its bounds)
  std::string where;            ///< "file:line scenario.acceptance[i]" for messages
};

/// The parsed section (empty without one).
struct Acceptance {
  std::vector<AcceptanceCriterion> criteria;
};

/// Parses and checks scenario.acceptance before anything runs. Throws InputError naming
/// file:line and the key (a wrong type, a missing figure or bound, min > max, a malformed key
/// path, an unknown top-level key or robot name).
Acceptance ParseAcceptance(const Scenario& scenario);

/// The outcome of one criterion.
struct CriterionResult {
  AcceptanceCriterion criterion;
  std::optional<double> value;  ///< the figure (nullopt: null in the report)
  bool passed = false;
  std::string message;          ///< "figure = 0.41 > max 0.3 (over by 0.11)"
};

/// All criteria's outcomes.
struct AcceptanceVerdict {
  std::vector<CriterionResult> results;
  bool passed() const;
};

/// The criteria without those on figures against the truth, or on the twin's own settings, which
/// a report without truth has as null or not at all (the list is in acceptance.cc), for a run
/// on a cell that has none; unless `quiet`, a line on stdout names each one left out.
Acceptance WithoutTruthCriteria(const Acceptance& acceptance, bool quiet);

/// A report's `truth` key on a cell without truth (a real cell, `serve-cell --no-truth`):
/// available false, and a reason that ends with `holds`, what the report holds instead.
nlohmann::json TruthUnavailableJson(const std::string& holds);

/// Evaluates the criteria on the finished report and adds report["acceptance"] (the results).
/// Throws InputError (naming the criterion's file:line) for a figure that is not in the report
/// or not a number.
AcceptanceVerdict EvaluateAcceptance(const Acceptance& acceptance, nlohmann::json* report);

/// The JUnit XML text: one testsuite named after the scenario, one test case per criterion
/// (a failure element for each missed one), `time_s` the run's wall time.
std::string JunitXml(const std::string& suite, const AcceptanceVerdict& verdict, double time_s);

/// Refuses a --junit path before anything runs (InputError naming "--junit"): what
/// ValidateOutputFile refuses, an existing file that is not a JUnit file twinbench wrote, or a
/// path inside the output folder `out_dir` (which the run replaces whole).
void ValidateJunitFile(const std::string& path, const std::string& out_dir);

/// Writes JunitXml to `path` atomically (InputError naming the path on failure).
void WriteJunit(const std::string& path, const std::string& suite,
                const AcceptanceVerdict& verdict, double time_s);

/// One line per criterion ("acceptance: passed ..." / "acceptance: FAILED ..."), nothing
/// without criteria.
void PrintVerdict(const AcceptanceVerdict& verdict, std::ostream& out);
/// As above, to stdout.
void PrintVerdict(const AcceptanceVerdict& verdict);

/// 0 when every criterion passed, kExitAcceptanceFailed otherwise.
int VerdictExitCode(const AcceptanceVerdict& verdict);

}  // namespace twin
