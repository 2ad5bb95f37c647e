#include "bench/report/calibration_report.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "bench/report/acceptance.h"
#include "bench/report/diagnosis_report.h"
#include "bench/report/report_html.h"
#include "bench/report/scenario_json.h"
#include "calib/common/frames.h"
#include "calib/model/parameters.h"

namespace twin {
namespace {
using json = nlohmann::json;

// JSON number, or null for NaN / infinity (JSON has neither).
json Num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
json Mm(double m) { return Num(1000.0 * m); }

json Misaligned(const MisalignedSummary& m) {
  // No samples (e.g. no validation axis aligned): every figure is there, null, so that an
  // acceptance criterion on it fails as "has no value" instead of naming an unknown figure.
  if (m.samples == 0) {
    return json{{"before", nullptr}, {"after", nullptr}, {"decrease_percent", nullptr},
                {"samples", 0}};
  }
  return json{{"before", Mm(m.before)},
              {"after", Mm(m.after)},
              {"decrease_percent", Num(DecreasePercent(m.before, m.after))},
              {"samples", m.samples}};
}

json Stats(const PositionErrorStats& s) { return json{{"rms", Mm(s.rms)}, {"max", Mm(s.max)}}; }

json Gauges(int configurations, const GaugeErrors& before, const GaugeErrors& after) {
  json j;
  j["configurations"] = configurations;
  j["raw"] = {{"before", Stats(before.raw)}, {"after", Stats(after.raw)}};
  j["rigid"] = {{"before", Stats(before.rigid)}, {"after", Stats(after.rigid)}};
  j["similarity"] = {{"before", Stats(before.similarity)}, {"after", Stats(after.similarity)}};
  return j;
}

json Gauges(const RobotScore& s) { return Gauges(s.configurations, s.before, s.after); }

json IntrinsicsJson(const PinholeIntrinsics& k, const DistortionCoefficients& d) {
  return json{{"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy}, {"k1", d.k1},
              {"k2", d.k2}, {"p1", d.p1}, {"p2", d.p2}, {"k3", d.k3}};
}


// The printed plate Zhang's method saw: the intrinsics target when the cell was told one.
json PlateJson(const CalibrationStageResult& s) {
  const BoardGeometry& p = s.plate;
  return json{{"squares", {p.squares_x, p.squares_y}},
              {"square_mm", p.square_m * 1e3},
              {"dedicated_target", s.dedicated_target}};
}

// The report's `intrinsics` key: Zhang's estimate against the twin camera's truth, and the plate.
json IntrinsicsReportJson(const CalibrationStageResult& s) {
  const OpticalAxisResult& result = s.procedure;
  const PinholeIntrinsics& ti = s.true_intrinsics;
  const PinholeIntrinsics& ei = result.intrinsics.intrinsics;
  return json{
      {"estimated", IntrinsicsJson(ei, result.intrinsics.distortion)},
      {"true", IntrinsicsJson(ti, s.true_distortion)},
      {"error_px",
       {{"fx", ei.fx - ti.fx}, {"fy", ei.fy - ti.fy}, {"cx", ei.cx - ti.cx}, {"cy", ei.cy - ti.cy}}},
      {"rms_reprojection_px", result.intrinsics.rms_px},
      {"views_used", result.intrinsics.views_used},
      {"views_skipped", result.intrinsics.skipped},
      {"plate", PlateJson(s)}};
}

// A robot's `planning` key: the pose plan, its PSO runs and the candidates' rejections.
json PlanningJson(const RobotCalibration& rc, const PosePlannerOptions& planner) {
  json history = json::array();
  for (const auto& run : rc.plan.fitness_history) history.push_back(run);
  const RejectionCounts& rej = rc.plan.rejections;
  return json{{"axes", rc.plan.axes.size()},
              {"positions_per_axis", planner.positions_per_axis},
              {"best_fitness", Num(rc.plan.best_fitness)},
              {"best_run", rc.plan.best_run},
              {"select_run", planner.select_run ==
                                     PosePlannerOptions::RunSelection::kPredictedError
                                 ? "predicted_error"
                                 : "best_fitness"},
              {"run_fitness", rc.plan.run_fitness},
              {"run_predicted_error_mm", [&] {
                 json e = json::array();
                 for (double x : rc.plan.run_predicted_error) e.push_back(Num(1e3 * x));
                 return e;
               }()},
              {"run_predicted_similarity_error_mm", [&] {
                 json e = json::array();
                 for (double x : rc.plan.run_predicted_similarity_error) {
                   e.push_back(Num(1e3 * x));
                 }
                 return e;
               }()},
              {"evaluations", rc.plan.evaluations},
              {"fitness_history", history},
              {"rejections",
               {{"active_ik", rej.active_ik}, {"passive_ik", rej.passive_ik},
                {"c1_joint_limits", rej.c1_joint_limits},
                {"c2_singularity", rej.c2_singularity},
                {"c3_visibility", rej.c3_visibility},
                {"c4_min_distance", rej.c4_min_distance},
                {"c5_max_distance", rej.c5_max_distance}}},
              {"time_s", rc.plan_compute_s},
              {"wait_time_s", rc.planning_s},
              {"from_plan_store", rc.plan_from_store}};
}


// A robot's `split` key: its calibration and validation axes and how they were chosen.
json SplitJson(const RobotCalibration& rc) {
  json split = {{"calibration_axes", rc.calibration_axes},
                {"validation_axes", rc.validation_axes},
                {"rule", rc.split_candidates.empty() ? "first" : "best_conditioned"},
                {"evaluated_at", rc.split_candidates.empty() ? json(nullptr) : json(rc.split_at)}};
  for (const auto& [axes, sigma] : rc.split_candidates) {
    split["candidates"].push_back({{"calibration_axes", axes},
                                   {"smallest_singular_value", sigma}});
  }
  return split;
}

// A robot's `misaligned_error_mm` key: eq. 46 per set and per axis, before and after.
json MisalignedErrorJson(const RobotCalibration& rc) {
  json per_axis = json::array();
  for (size_t k = 0; k < rc.per_axis.size(); ++k) {
    const int axis = static_cast<int>(k);
    const bool cal = std::find(rc.calibration_axes.begin(), rc.calibration_axes.end(),
                               axis) != rc.calibration_axes.end();
    if (rc.per_axis[k].samples == 0) continue;
    per_axis.push_back({{"axis", axis}, {"set", cal ? "calibration" : "validation"},
                        {"before", Mm(rc.per_axis[k].before)},
                        {"after", Mm(rc.per_axis[k].after)}});
  }
  return json{{"calibration", Misaligned(rc.calibration_error)},
              {"validation", Misaligned(rc.validation_error)},
              {"per_axis", per_axis}};
}


// A robot's `identifiable_combinations` key: the observable combinations against truth, with
// the identification's covariance.
json IdentifiableCombinationsJson(const RobotCalibration& rc, const RobotScore& score,
                                  const ObservabilityReport& obs) {
  json combos = json::array();
  const IdentificationCovariance& cov = rc.covariance;
  for (size_t i = 0; i < score.combination_estimated.size(); ++i) {
    const bool has_sigma = cov.ok && static_cast<int>(i) < cov.sigma_z.size();
    combos.push_back({{"index", i}, {"estimated", 1000 * score.combination_estimated[i]},
                      {"true", 1000 * score.combination_true[i]},
                      {"sigma", has_sigma ? json(1000 * cov.sigma_z(i)) : json(nullptr)}});
  }
  json combinations = {{"count", obs.rank},
                       {"unit", "mm or mrad (scaled coordinates, 1 m)"},
                       {"rms_error", 1000 * score.combination_rms_error},
                       {"max_error", 1000 * score.combination_max_error},
                       {"items", combos}};
  combinations["covariance"] = {
      {"status", cov.ok ? "ok" : "not_estimated"},
      {"reason", cov.reason},
      {"residual_sigma_mm", 1000 * cov.residual_sigma},
      {"redundancy", cov.redundancy}};
  return combinations;
}

// A robot's `parameters` key: each parameter estimated against truth, in mm or deg.
json ParametersJson(const RobotScore& score, const IdentificationCovariance& cov) {
  json params = json::array();
  for (size_t k = 0; k < score.parameters.size(); ++k) {
    const ParameterComparison& p = score.parameters[k];
    const double f = p.length ? 1000.0 : RadToDeg(1.0);
    const bool has_sigma = cov.ok && static_cast<int>(k) < cov.sigma_parameters.size();
    params.push_back({{"name", p.name}, {"unit", p.length ? "mm" : "deg"},
                      {"estimated", f * p.estimated}, {"true", f * p.truth},
                      {"sigma", has_sigma ? json(f * cov.sigma_parameters(k)) : json(nullptr)}});
  }
  return params;
}

// A robot's `identification` key: both methods' outcomes, the refit and their difference.
json IdentificationJson(const RobotCalibration& rc) {
  const LinearizedIdentificationResult& lin = rc.linearized;
  const NonlinearIdentificationResult& nl = rc.nonlinear;
  json eps = json::array();
  for (double e : lin.eps_history) eps.push_back(1000 * e);
  return json{
      {"method", rc.method},
      {"time_s", rc.identification_s},
      {"linearized",
       {{"status", ToString(lin.status)}, {"reason", lin.reason}, {"iterations", lin.iterations},
        {"rank", lin.observability.rank}, {"eps_history_mm", eps},
        {"calibration_after_mm", Mm(lin.mean_misaligned_error_after)}}},
      {"nonlinear",
       {{"status", ToString(nl.status)}, {"iterations", nl.iterations},
        {"rank", nl.observability.rank}, {"passes", nl.passes},
        {"depth_used", nl.depth_used},
        {"singular_values", nl.observability.singular_values},
        {"depth_weight", nl.depth_weight},
        {"rms_distance_before_mm", Mm(nl.rms_distance_before)},
        {"rms_distance_after_mm", Mm(nl.rms_distance_after)},
        {"rms_depth_residual_mm", Mm(nl.rms_depth_residual)}}},
      {"delivered_model", rc.refit ? "all axes (refit after validation)" : "calibration axes"},
      {"refit_all_axes",
       rc.refit ? json{{"status", ToString(rc.refit_result.status)},
                       {"axes", rc.calibration_axes.size() + rc.validation_axes.size()},
                       {"rank", rc.refit_result.observability.rank},
                       {"passes", rc.refit_result.passes},
                       {"rms_distance_after_mm", Mm(rc.refit_result.rms_distance_after)},
                       {"rms_depth_residual_mm", Mm(rc.refit_result.rms_depth_residual)}}
                : json(nullptr)},
      {"linearized_vs_ceres_max_parameter_difference",
       lin.status == LinearizedIdentificationStatus::kSkipped ? json(nullptr) : json
       {{"mm", 1000 * [&] {
           double m = 0;
           for (int i = 0; i < lin.correction.size(); ++i)
             if (IsLengthParameter(i))
               m = std::max(m, std::abs(lin.correction(i) - nl.correction(i)));
           return m;
         }()},
        {"deg", RadToDeg([&] {
           double m = 0;
           for (int i = 0; i < lin.correction.size(); ++i)
             if (!IsLengthParameter(i))
               m = std::max(m, std::abs(lin.correction(i) - nl.correction(i)));
           return m;
         }())}}}};
}


// Both models' raw and rigid gauges against the measured truth, with the poses and `rule`.
json PhysicalGaugesJson(const PhysicalTruthScore& p) {
  const GaugeErrors& calibrated = p.calibrated;
  const GaugeErrors& discovered = p.discovered;
  return json{
      {"poses", p.poses},
      {"rule", p.rule},
      {"calibrated_model", {{"raw", Stats(calibrated.raw)}, {"rigid", Stats(calibrated.rigid)}}},
      {"discovered_model", {{"raw", Stats(discovered.raw)}, {"rigid", Stats(discovered.rigid)}}}};
}


// identification.json: the method, eq. 46 errors, unidentifiable parameters, scale and the
// corrections to the nominal model (mm or deg).
json IdentificationSummaryJson(const RobotCalibration& rc, const std::string& robot) {
  json j;
  j["robot"] = robot;
  j["method"] = rc.method;
  j["samples"] = rc.samples.size();
  j["misaligned_error_mm"] = {{"calibration", Misaligned(rc.calibration_error)},
                              {"validation", Misaligned(rc.validation_error)}};
  const NonlinearIdentificationResult& nl = rc.nonlinear;
  j["unidentifiable"] = (rc.method == "linearized" ? rc.linearized : rc.linearized).observability
                            .unidentifiable;
  if (rc.method != "linearized") j["unidentifiable"] = nl.observability.unidentifiable;
  j["scale"] = {{"identified_length_ratio", nl.scale}, {"depth_used", nl.depth_used}};
  json corr = json::object();
  const ParameterVector d = GetParameters(rc.identified) - GetParameters(rc.nominal);
  for (int i = 0; i < d.size(); ++i) {
    corr[ParameterName(robot, i)] = IsLengthParameter(i) ? 1000 * d(i) : RadToDeg(d(i));
  }
  j["correction_mm_or_deg"] = corr;
  return j;
}


// A robot's `servo` key: aligned and failed poses, frames, final errors, the images written.
json ServoJson(const RobotCalibration& rc, const RobotStageResult& s, double tolerance_px) {
  json failures = json::array();
  for (const FailedPose& f : rc.failed) {
    failures.push_back({{"axis", f.axis}, {"index", f.index}, {"status", f.status},
                        {"reason", f.reason}, {"frames", f.frames}});
  }
  json images = json::array();
  for (const ReportImage& im : s.images) {
    images.push_back({{"file", im.file}, {"caption", im.caption}});
  }
  const int aligned = static_cast<int>(rc.aligned.size());
  return json{{"aligned_poses", aligned},
              {"failed_poses", rc.failed.size()},
              {"mean_frames_per_pose",
               aligned > 0 ? json(double(s.servo.frames) / aligned) : json()},
              {"max_final_pixel_error_px", s.servo.max_final_pixel_error_px},
              {"region_frames", s.servo.region_frames},
              {"full_frame_fallbacks", s.servo.full_frame_fallbacks},
              {"tolerance_px", tolerance_px},
              {"failures", failures},
              {"images", images},
              {"time_s", rc.servoing_s}};
}

// A robot's `truth_position_error_mm_covered_region` key: the truth errors over the joint box
// of the poses the delivered model was fitted on.
json CoveredRegionJson(const CoveredRegionScore& c) {
  json joints = json::array();
  for (int i = 0; i < c.box.lower.size(); ++i) {
    joints.push_back({{"joint", i + 1}, {"lower_deg", RadToDeg(c.box.lower(i))},
                      {"upper_deg", RadToDeg(c.box.upper(i))}});
  }
  json covered = Gauges(c.score.configurations, c.score.before, c.score.after);
  covered["poses"] = c.poses;
  covered["joint_box_deg"] = joints;
  return covered;
}

// Sets a robot's `diagnosis` key (and `declared_terms` where the diagnosis ran).
void AddDiagnosisJson(const RobotDiagnosisResult& d, json* r) {
  if (d.result) {
    (*r)["diagnosis"] = DiagnosisJson(*d.result);
    (*r)["declared_terms"] = d.declared_terms;
  } else {
    (*r)["diagnosis"] = {{"verdict", nullptr}, {"skipped", d.skipped}};
  }
}

// Sets a robot's physical-truth keys, as far as they were measured.
void AddPhysicalTruthJson(const RobotStageResult& s, json* r) {
  if (s.physical_skipped) {
    (*r)["truth_position_error_mm_physical"] = {{"skipped", *s.physical_skipped}};
  }
  if (s.physical) {
    (*r)["truth_position_error_mm_physical"] = PhysicalGaugesJson(*s.physical);
    (*r)["truth_position_error_mm_discovered_model"] =
        (*r)["truth_position_error_mm_physical"]["discovered_model"];
  }
  if (s.physical_covered_region) {
    (*r)["truth_position_error_mm_physical_covered_region"] =
        PhysicalGaugesJson(*s.physical_covered_region);
  }
}

// One robot's report entry: planning, servo, split, errors against truth, identification,
// diagnosis and physical truth.
json RobotReportJson(const RobotCalibration& rc, const RobotStageResult& s,
                     const CalibrationStageResult& stage) {
  const ObservabilityReport& obs = s.observability;
  json r;
  r["camera_robot"] = s.camera_robot;
  r["planning"] = PlanningJson(rc, stage.planner);
  r["servo"] = ServoJson(rc, s, stage.servo_tolerance_px);
  if (std::isfinite(rc.temperature_reference_C)) {
    r["temperature_reference_C"] = rc.temperature_reference_C;
  }
  r["split"] = SplitJson(rc);
  r["misaligned_error_mm"] = MisalignedErrorJson(rc);
  if (stage.truth_available) r["truth_position_error_mm"] = Gauges(s.score);
  if (s.covered_region) {
    r["truth_position_error_mm_covered_region"] = CoveredRegionJson(*s.covered_region);
  }
  if (s.calibration_set_model) {
    r["truth_position_error_mm_calibration_set_model"] = Gauges(*s.calibration_set_model);
  }
  r["scale"] = {{"estimated", s.score.scale_estimated}, {"true", s.score.scale_true},
                {"identified_length_ratio",
                 rc.refit ? rc.refit_result.scale : rc.nonlinear.scale}};
  r["unidentifiable"] = obs.unidentifiable;
  r["identifiable_combinations"] = IdentifiableCombinationsJson(rc, s.score, obs);
  r["parameters"] = ParametersJson(s.score, rc.covariance);
  r["identification"] = IdentificationJson(rc);
  AddDiagnosisJson(s.diagnosis, &r);
  AddPhysicalTruthJson(s, &r);
  return r;
}

// The report's `timing_s` key: the stages' times and the cell's frames and moves.
json TimingJson(const CalibrationTiming& t) {
  return json{{"total", t.total}, {"intrinsics", t.intrinsics},
              {"intrinsics_detection", t.intrinsics_detection},
              {"intrinsics_zhang", t.intrinsics_zhang},
              {"planning", t.planning},      {"planning_compute", t.planning_compute},
              {"servoing", t.servoing},
              {"identification", t.identification}, {"diagnosis", t.diagnosis},
              {"scoring", t.scoring},
              {"cell",
               {{"frames", t.frames},
                {"region_frames", t.region_frames},
                {"region_mean_pixels",
                 t.region_frames > 0 ? json(t.region_pixels / t.region_frames) : json(nullptr)},
                {"grab_image", t.grab_image},
                {"moves", t.moves},
                {"move_to", t.move_to},
                {"renderer", t.renderer.empty() ? json(nullptr) : json(t.renderer)}}}};
}

}  // namespace

json CalibrationStageJson(const Scenario& scenario, const CalibrationStageResult& stage) {
  json report;
  report["scenario"] = ScenarioJson(scenario);
  report["intrinsics"] = IntrinsicsReportJson(stage);
  json robots = json::object();
  for (size_t i = 0; i < stage.robots.size(); ++i) {
    robots[stage.robots[i].name] =
        RobotReportJson(stage.procedure.robots[i], stage.robots[i], stage);
  }
  report["robots"] = robots;
  if (!stage.truth_available) {
    report["truth"] = TruthUnavailableJson("the estimates alone, every true value null");
  }
  report["timing_s"] = TimingJson(stage.timing);
  return report;
}

JudgedReport JudgeReport(json report, const Acceptance& acceptance, bool html) {
  JudgedReport out;
  out.verdict = EvaluateAcceptance(acceptance, &report);
  out.json = report.dump(2) + "\n";
  if (html) out.html = RenderReportHtml(report);
  return out;
}

JudgedReport CalibrationReport(const Scenario& scenario, const CalibrationStageResult& stage,
                               const Acceptance& acceptance, bool html) {
  return JudgeReport(CalibrationStageJson(scenario, stage), acceptance, html);
}

std::string IdentificationReportText(const RobotCalibration& rc, const std::string& robot) {
  return IdentificationSummaryJson(rc, robot).dump(2) + "\n";
}

}  // namespace twin
