#include "bench/runs/tracker_identify_run.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <fstream>
#include <iostream>
#include <optional>

#include "bench/io/model_loader.h"
#include "bench/io/model_yaml.h"
#include "bench/io/output_files.h"
#include "bench/io/term_spec_text.h"
#include "bench/io/tracker_file.h"
#include "bench/report/diagnosis_report.h"
#include "bench/report/tracker_identify_report.h"
#include "calib/common/errors.h"
#include "calib/diagnosis/model_discovery.h"
#include "calib/model/robot_model.h"
#include "calib/procedures/tracker_calibration.h"

namespace twin {
namespace fs = std::filesystem;

namespace {

void WriteFile(const fs::path& path, const std::string& text) { WriteTextFile(path.string(), text); }

// Smallest range of a joint over a tracker file below which its axis is named as a cause of
// a lower rank: a calibration moves every joint tens of degrees, and under 1 deg the
// parameters its motion separates are at the noise of a few micrometres.
constexpr double kMinJointSpan = 3.14159265358979323846 / 180.0;  // [rad]

/// What `identify` reads: the nominal chain, the tracker files and the model it starts from.
struct IdentifyInputs {
  KinematicModel chain;    ///< the nominal model as loaded
  TrackerFile file;        ///< the measurements
  TrackerFile validation;  ///< the --validate file (no points without one)
  RobotModel nominal;      ///< the chain with the declared terms
};

/// What `identify` finds: the calibration, the model discovery and what lowers the rank.
struct IdentifyOutcome {
  TrackerCalibrationResult calibration;  ///< identification with held-out scoring
  DiscoveryResult diagnosis;             ///< model discovery (empty with --no-diagnosis)
  std::vector<std::string> rank_causes;  ///< sentences naming what lowers the rank
};

// Checks the options, reads the model and the files and adds the declared terms; throws
// InputError before anything is written.
IdentifyInputs ReadIdentifyInputs(const TrackerIdentifyOptions& o) {
  ValidateOutputFolder(o.out_dir, "--out");
  if (!(o.holdout_fraction > 0.0 && o.holdout_fraction <= 0.5)) {
    throw InputError("--holdout", "expected a fraction in (0, 0.5], got " +
                                      std::to_string(o.holdout_fraction));
  }
  IdentifyInputs in;
  in.chain = LoadRobotModelAndWarn(o.model, o.links);
  const KinematicModel& chain = in.chain;
  in.file = ReadTrackerFile(o.measurements, chain, o.ignore_columns);
  if (!o.validate.empty()) in.validation = ReadTrackerFile(o.validate, chain, o.ignore_columns);
  RobotModel& nominal = in.nominal;
  nominal = MakeRobotModel(chain);
  for (const std::string& text : o.declared_terms) {
    const std::string where = "--declare " + text;
    nominal = WithTerm(nominal, MakeErrorTerm(ParseTermSpec(text, where), chain, chain.name, where));
  }
  for (const TrackerPoint& p : in.file.points) {
    const std::string missing = MissingContext(nominal, p.context);
    if (!missing.empty()) {
      throw InputError(o.measurements + ":" + std::to_string(p.row),
                       "a declared term needs what this row lacks: " + missing);
    }
  }
  return in;
}

// Model discovery's options from the command line, checked when discovery runs.
DiscoveryOptions IdentifyDiscoveryOptions(const TrackerIdentifyOptions& o) {
  DiscoveryOptions discovery;
  discovery.alpha = o.diagnosis_alpha;
  discovery.min_gain_percent = o.diagnosis_min_gain_percent;
  discovery.max_effects = o.diagnosis_max_effects;
  discovery.folds = o.diagnosis_folds;
  discovery.jobs = o.jobs;
  discovery.joint_sigma_rad = DegToRad(o.encoder_sigma_deg);
  discovery.seed = o.seed;
  discovery.session_scoring.seed = o.seed;  // the calibration's halvings: one paired comparison
  discovery.set.source = o.measurements;
  if (!o.quiet) {
    discovery.progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  }
  if (o.diagnosis) ValidateDiscoveryOptions(discovery);
  return discovery;
}

// The identification with held-out scoring; its errors name the measurements file.
TrackerCalibrationResult CalibrateTrackerFile(const TrackerIdentifyOptions& o,
                                              const IdentifyInputs& in) {
  TrackerCalibrationOptions options;
  options.holdout_fraction = o.holdout_fraction;
  options.seed = o.seed;
  options.session.seed = o.seed;  // the diagnosis's halvings too (IdentifyDiscoveryOptions)
  options.set.source = o.measurements;
  TrackerCalibrationResult r;
  try {
    r = CalibrateFromTracker(in.nominal, in.file.points, in.validation.points, options);
  } catch (const InputError& e) {
    if (e.where().rfind(o.measurements, 0) == 0) throw;
    throw InputError(o.measurements, e.what());
  }
  return r;
}

// Model discovery from the file's points (when it is asked for); its errors name the file.
DiscoveryResult DiscoverTrackerFileModel(const TrackerIdentifyOptions& o, const IdentifyInputs& in,
                                         const DiscoveryOptions& discovery) {
  DiscoveryResult diagnosis;
  if (o.diagnosis) {
    // The second session (--validate) is scored, never trained on (issue 39).
    DiscoveryOptions with_session = discovery;
    with_session.session = in.validation.points;
    try {
      diagnosis = DiscoverTrackerModel(in.nominal, in.file.points, with_session);
    } catch (const InputError& e) {
      if (e.where().rfind(o.measurements, 0) == 0) throw;
      throw InputError(o.measurements, e.what());
    }
  }
  return diagnosis;
}

// What lowers the rank, named: joints the file hardly moves, and poses measured again.
std::vector<std::string> RankCauses(const KinematicModel& chain, const TrackerFile& file,
                                    const IdentificationResult& id) {
  std::vector<std::string> rank_causes;
  for (int k = 0; k < chain.num_joints(); ++k) {
    double lo = INFINITY, hi = -INFINITY;
    for (const TrackerPoint& p : file.points) {
      lo = std::min(lo, p.context.q(k));
      hi = std::max(hi, p.context.q(k));
    }
    if (hi - lo < kMinJointSpan) {
      std::ostringstream os;
      os.precision(3);
      os << "joint " << k + 1 << " (column " << file.joint_columns[k] << ") spans only "
         << RadToDeg(hi - lo) << " deg over the file's poses: the parameters that only its "
         << "motion tells apart are not identifiable (" << id.observability.unidentifiable.size()
         << " unidentifiable combinations, rank " << id.observability.rank << ")";
      rank_causes.push_back(os.str());
    }
  }
  if (file.distinct_poses < static_cast<int>(file.points.size())) {
    rank_causes.push_back(std::to_string(file.points.size()) + " rows measure " +
                          std::to_string(file.distinct_poses) +
                          " different poses: a repeat adds no direction to the identification");
  }
  return rank_causes;
}

// The identification's typed result, as its report reads it.
TrackerIdentifyResult MakeIdentifyResult(const TrackerIdentifyOptions& o, const IdentifyInputs& in,
                                         const IdentifyOutcome& outcome) {
  TrackerIdentifyResult r;
  r.file = o.measurements;
  r.model = o.model;
  r.robot = in.chain.name;
  r.measurements = &in.file;
  r.rank_causes = outcome.rank_causes;
  r.calibration = &outcome.calibration;
  for (const auto& t : in.nominal.terms) r.declared_terms.push_back(TermLabel(t->spec()));
  if (o.diagnosis) r.diagnosis = &outcome.diagnosis;
  return r;
}

// Writes report.json, report.html and identified_<robot>.yaml into a staging folder and
// publishes it as the output folder (nothing is left behind on an error).
void WriteIdentifyOutputs(const TrackerIdentifyOptions& o, const KinematicModel& chain,
                          const TrackerIdentifyReport& report, const IdentificationResult& id) {
  const fs::path out(o.out_dir);
  const std::string staging = CreateStagingDirectory(o.out_dir);
  try {
    WriteFile(fs::path(staging) / "report.json", report.json_text);
    WriteFile(fs::path(staging) / "report.html", report.html);
    WriteFile(fs::path(staging) / ("identified_" + chain.name + ".yaml"),
              ModelToYaml(id.model.chain));
    PublishDirectory(staging, out.string());
  } catch (...) {
    DiscardStaging(staging);
    throw;
  }
}

// The second session's line: each model's mean held-out RMS over the halvings, +- their
// standard deviation.
void PrintSessionLine(const SessionScore& nominal, const SessionScore& geometric,
                      const std::optional<SessionScore>& discovered) {
  std::printf("%-8s %-10d nominal %.4f +- %.4f, geometric %.4f +- %.4f", "session", nominal.points,
              1e3 * nominal.rms_m, 1e3 * nominal.rms_sd_m, 1e3 * geometric.rms_m,
              1e3 * geometric.rms_sd_m);
  if (discovered) {
    std::printf(", discovered %.4f +- %.4f", 1e3 * discovered->rms_m, 1e3 * discovered->rms_sd_m);
  }
  std::printf(" mm (validation file, tracker pose refitted on half; mean +- sd over %d "
              "halvings)\n",
              nominal.halvings);
}

// Prints the summary: the rank, each split's held-out errors, the diagnosis, the warnings
// and notes, and what was written.
void PrintIdentifySummary(const TrackerIdentifyOptions& o, const IdentifyInputs& in,
                          const IdentifyOutcome& outcome) {
  const KinematicModel& chain = in.chain;
  const TrackerFile& file = in.file;
  const TrackerCalibrationResult& r = outcome.calibration;
  const IdentificationResult& id = r.identified;
  const fs::path out(o.out_dir);
  std::printf("%s: %zu tracker points, %d identifiable combinations (condition %.3g), %zu "
              "unidentifiable\n",
              chain.name.c_str(), file.points.size(), id.observability.rank,
              id.condition_number(), id.observability.unidentifiable.size());
  std::printf("%-8s %-10s %28s %28s\n", "split", "held out", "before RMS / max [mm]",
              "after RMS / max [mm]");
  for (const HeldOutSplit& s : r.splits) {
    std::printf("%-8s %-10d %18.4f / %7.4f %18.4f / %7.4f%s\n", s.name.c_str(), s.after.poses,
                1e3 * s.before.rms, 1e3 * s.before.max, 1e3 * s.after.rms, 1e3 * s.after.max,
                s.worse ? "   WORSE" : "");
  }
  std::printf("%-8s %-10zu %18.4f / %7.4f %18.4f / %7.4f   (fitted, not held out)\n", "all",
              file.points.size(), 1e3 * r.all_before.rms, 1e3 * r.all_before.max,
              1e3 * r.all_after.rms, 1e3 * r.all_after.max);
  if (r.session_nominal) {
    PrintSessionLine(*r.session_nominal, *r.session_geometric,
                     o.diagnosis ? outcome.diagnosis.session_discovered : std::nullopt);
  }
  if (o.diagnosis) std::printf("%s", DiagnosisSummary(outcome.diagnosis).c_str());
  for (const std::string& w : r.warnings) std::fprintf(stderr, "WARNING: %s\n", w.c_str());
  if (o.diagnosis) {
    for (const std::string& w : outcome.diagnosis.warnings) {
      std::fprintf(stderr, "WARNING: %s\n", w.c_str());
    }
  }
  for (const std::string& c : outcome.rank_causes) std::fprintf(stderr, "note: %s\n", c.c_str());
  std::printf("wrote %s/report.json, report.html and identified_%s.yaml\n", out.string().c_str(),
              chain.name.c_str());
}

}  // namespace

int RunTrackerIdentify(const TrackerIdentifyOptions& o) {
  // Everything is validated before anything is written.
  const IdentifyInputs in = ReadIdentifyInputs(o);
  // Model discovery's options, checked before the identification runs.
  const DiscoveryOptions discovery = IdentifyDiscoveryOptions(o);
  IdentifyOutcome outcome;
  // The identification with held-out scoring.
  outcome.calibration = CalibrateTrackerFile(o, in);
  // Model discovery (skipped with --no-diagnosis).
  outcome.diagnosis = DiscoverTrackerFileModel(o, in, discovery);
  // What lowers the rank, named.
  outcome.rank_causes = RankCauses(in.chain, in.file, outcome.calibration.identified);
  // The report, written only once complete.
  const TrackerIdentifyReport report =
      MakeTrackerIdentifyReport(MakeIdentifyResult(o, in, outcome));
  WriteIdentifyOutputs(o, in.chain, report, outcome.calibration.identified);
  // The summary on the terminal.
  PrintIdentifySummary(o, in, outcome);
  return 0;
}

}  // namespace twin
