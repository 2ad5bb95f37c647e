#include "bench/report/handclasp_report.h"

#include "calib/common/frames.h"

namespace twin {
namespace {
using json = nlohmann::json;

json Xyz(const Vector3& p_m) { return {1e3 * p_m.x(), 1e3 * p_m.y(), 1e3 * p_m.z()}; }

json Zyz(const Matrix3& R) {
  const Vector3 a = ZyzFromRotation(R);
  return {RadToDeg(a(0)), RadToDeg(a(1)), RadToDeg(a(2))};
}

json PoseJson(const Transform& X) {
  return {{"xyz_mm", Xyz(X.translation())}, {"zyz_deg", Zyz(X.linear())}};
}

// An estimate, its errors against the kinematic-frame truth (eq. 33-34) and its fit residual.
json Scored(const Transform& estimate, const BaseFrameError& e, double rms_m) {
  json j = PoseJson(estimate);
  j["e_tran_mm"] = e.e_tran_mm;
  j["e_rot_deg"] = e.e_rot_deg;
  j["rms_residual_mm"] = 1e3 * rms_m;
  return j;
}

// The errors of one comparison.
json ErrorsJson(const BaseFrameError& e) {
  return json{{"e_tran_mm", e.e_tran_mm}, {"e_rot_deg", e.e_rot_deg}};
}

// installation, operator_error_mm and taught_points.
void AddTeaching(const HandclaspTeaching& t, json* rep) {
  (*rep)["installation"] = ToString(t.installation);
  (*rep)["operator_error_mm"] = 1e3 * t.operator_error_m;
  (*rep)["taught_points"] = {{"planned", t.planned},
                             {"cube_side_mm", 1e3 * t.taught.cube_side_m},
                             {"count", t.taught.points},
                             {"orientations_per_point", t.orientations_per_point},
                             {"poses", t.taught.q1.size()},
                             {"rejected", t.taught.rejected}};
}

// The per-robot link-1 offsets of KinematicBaseOffset.
json Link1Offsets(const HandclaspScoringFrames& s) {
  json j = json::array();
  for (int k = 0; k < 2; ++k) {
    j.push_back({{"dtheta1_deg", RadToDeg(s.dtheta1_rad[k])}, {"dd1_mm", 1e3 * s.dd1_m[k]}});
  }
  return j;
}

// truth, scoring_frame, physical_truth and pendant_tip_error.
void AddScoringFrames(const HandclaspScoringFrames& s, json* rep) {
  (*rep)["truth"] = PoseJson(s.truth);
  if (s.best_fit) {
    (*rep)["scoring_frame"] = {
        {"frames", "best fit: X_B1'B2' = X_B1B1'^-1 X_B1B2 X_B2B2', X_BB' the rigid transform "
                   "taking the pendant model's tip positions (identified tip corrections "
                   "applied) onto the true ones over 200 random joint configurations"},
        {"offsets", {PoseJson(s.X_BBp[0]), PoseJson(s.X_BBp[1])}}};
  } else {
    (*rep)["scoring_frame"] = {
        {"frames", "kinematic: X_B1'B2' = X_B1B1'^-1 X_B1B2 X_B2B2', B' = B X_BL0 RotZ(dtheta1) "
                   "TransZ(dd1) X_BL0^-1 with dtheta1, dd1 = true minus pendant link-1 theta, d "
                   "(unidentifiable by any kinematic calibration)"},
        {"link1_offsets", Link1Offsets(s)}};
  }
  (*rep)["physical_truth"] = PoseJson(s.physical);
  (*rep)["pendant_tip_error"] = json::array();
  for (const PendantTipError& e : s.pendant_tip_error) {
    (*rep)["pendant_tip_error"].push_back(
        {{"rms_mm", e.rms_mm}, {"max_mm", e.max_mm}, {"configurations", e.configurations}});
  }
}

// skipped, warnings and contacts (with residuals when the procedure succeeded).
void AddContacts(const HandclaspResult& result, json* rep) {
  (*rep)["skipped"] = result.skipped;
  (*rep)["warnings"] = result.calibration.warnings;
  json contacts = json::array();
  const BaseCalibrationResult& cal = result.calibration;
  for (const HandclaspContact& c : result.contacts) {
    json j = {{"point", c.point}, {"p_B1_mm", Xyz(c.p_B1)}, {"p_B2_mm", Xyz(c.p_B2)}};
    if (result.ok()) {
      j["residual_general_mm"] = 1e3 * (c.p_B1 - cal.X_B1B2_general * c.p_B2).norm();
      j["residual_constrained_mm"] = 1e3 * (c.p_B1 - cal.X_B1B2_constrained * c.p_B2).norm();
    }
    contacts.push_back(j);
  }
  (*rep)["contacts"] = contacts;
}

// general and constrained, with their physical errors under physical_truth.
void AddEstimates(const HandclaspStageResult& r, json* rep) {
  const BaseCalibrationResult& cal = r.procedure.calibration;
  (*rep)["general"] =
      Scored(r.X_B1B2_general, r.general.kinematic, cal.rms_residual_general_m);
  (*rep)["constrained"] =
      Scored(r.X_B1B2_constrained, r.constrained.kinematic, cal.rms_residual_constrained_m);
  if (!r.truth_available) return;
  (*rep)["physical_truth"]["general"] = ErrorsJson(r.general.physical);
  (*rep)["physical_truth"]["constrained"] = ErrorsJson(r.constrained.physical);
}

// tips_identified, and the estimate with the tips under physical_truth when identified.
void AddIdentifiedTips(const HandclaspStageResult& r, json* rep) {
  const TipRefinementResult& tips = r.procedure.tips;
  json& t = (*rep)["tips_identified"];
  t["status"] = tips.ok ? "ok" : "failed";
  t["relative_singular_value"] = tips.relative_singular_value;
  if (tips.ok) {
    t.update(Scored(tips.X_B1B2, r.tips.kinematic, tips.rms_residual_m));
    t["rms_residual_before_mm"] = 1e3 * tips.rms_residual_before_m;
    t["dt_flange_mm"] = {Xyz(tips.dt1_F1), Xyz(tips.dt2_F2)};
    t["sigma_dt_flange_mm"] = {Xyz(tips.sigma_dt1_F1), Xyz(tips.sigma_dt2_F2)};
    if (r.truth_available) {
      (*rep)["physical_truth"]["tips_identified"] = ErrorsJson(r.tips.physical);
    }
  } else {
    t["reason"] = tips.reason;
  }
}

// The stage from scoring on: frames, contacts, the estimates or why there are none.
void AddScoredStage(const HandclaspStageResult& r, json* rep) {
  if (r.truth_available) AddScoringFrames(r.frames, rep);
  AddContacts(r.procedure, rep);
  if (!r.ok()) {
    (*rep)["status"] = "failed";
    (*rep)["reason"] = r.reason;
    return;
  }
  (*rep)["status"] = "ok";
  AddEstimates(r, rep);
  if (r.tips_attempted) AddIdentifiedTips(r, rep);
  if (r.coupled_motion) (*rep)["coupled_motion"] = CoupledMotionJson(*r.coupled_motion);
}

// Means over the n trials of one estimate's errors, kinematic or physical.
json MeanErrors(const std::vector<HandclaspStageResult>& done, int n,
                ScoredBaseFrame HandclaspStageResult::*which, bool physical) {
  double tran = 0, rot = 0;
  for (const HandclaspStageResult& r : done) {
    const BaseFrameError& e = physical ? (r.*which).physical : (r.*which).kinematic;
    tran += e.e_tran_mm;
    rot += e.e_rot_deg;
  }
  return json{{"mean_e_tran_mm", tran / n}, {"mean_e_rot_deg", rot / n}};
}

// base_frame.batch: counts, the mean errors and each trial's report.
json BatchSummary(const HandclaspBatchResult& b) {
  const int n = b.trials - b.failures;
  json batch = {{"trials", b.trials}, {"failed", b.failures}};
  if (n > 0) {
    int worse_tran = 0, worse_rot = 0;  // trials where the constrained one was worse
    for (const HandclaspStageResult& r : b.done) {
      worse_tran += r.constrained.kinematic.e_tran_mm > r.general.kinematic.e_tran_mm;
      worse_rot += r.constrained.kinematic.e_rot_deg > r.general.kinematic.e_rot_deg;
    }
    batch["general"] = MeanErrors(b.done, n, &HandclaspStageResult::general, false);
    batch["constrained"] = MeanErrors(b.done, n, &HandclaspStageResult::constrained, false);
    batch["physical_truth"] = {
        {"general", MeanErrors(b.done, n, &HandclaspStageResult::general, true)},
        {"constrained", MeanErrors(b.done, n, &HandclaspStageResult::constrained, true)}};
    batch["constrained_worse_e_tran_trials"] = worse_tran;
    batch["constrained_worse_e_rot_trials"] = worse_rot;
  }
  json trials = json::array();
  for (const HandclaspStageResult& r : b.done) trials.push_back(HandclaspStageJson(r));
  batch["trials_detail"] = trials;
  return batch;
}

}  // namespace

json CoupledMotionJson(const CoupledMotionResult& check) {
  json out;
  if (!check.skipped.empty()) {
    out["status"] = "skipped";
    out["reason"] = check.skipped;
  } else if (!check.ok) {
    out["status"] = "failed";
    out["reason"] = check.reason;
  } else {
    out["status"] = "ok";
    out["deviation_mm"] = check.deviation_mm;
    out["max_deviation_mm"] = check.max_deviation_mm;
  }
  out["estimate"] = check.estimate;
  return out;
}

json HandclaspStageJson(const HandclaspStageResult& stage) {
  json rep;
  AddTeaching(stage.teaching, &rep);
  if (stage.status == HandclaspStageStatus::kTeachingFailed) {
    rep["status"] = "failed";
    rep["reason"] = stage.reason;
  } else {
    AddScoredStage(stage, &rep);
  }
  if (stage.seed) rep["seed"] = *stage.seed;
  return rep;
}

std::string HandclaspReportText(const Scenario& scenario, const HandclaspBatchResult& batch,
                                const Acceptance& acceptance, AcceptanceVerdict* verdict) {
  json report;
  report["scenario"] = scenario.name;
  report["procedure"] = "handclasp base-frame calibration (Gan et al. 2014)";
  report["status"] = batch.failures == 0 ? "ok" : "failed";
  // trial 0: the scenario's own seed
  report["base_frame"] = batch.done.empty() ? json() : HandclaspStageJson(batch.done.front());
  if (batch.trials > 1) report["base_frame"]["batch"] = BatchSummary(batch);
  if (!batch.done.empty() && !batch.done.front().truth_available) {
    report["truth"] = TruthUnavailableJson(
        "the estimates alone, their errors null, the coupled-motion check skipped");
  }
  *verdict = EvaluateAcceptance(acceptance, &report);
  return report.dump(2) + "\n";
}

}  // namespace twin
