#include "bench/runs/handclasp_run.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "bench/io/model_loader.h"
#include "bench/io/output_files.h"
#include "bench/io/scenario_keys.h"
#include "bench/report/acceptance.h"
#include "bench/report/handclasp_report.h"
#include "bench/runs/calibration_run.h"
#include "bench/scoring/calibration_scoring.h"
#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "calib/procedures/handclasp_procedure.h"
#include "calib/kinematics/inverse_kinematics.h"
#include "sim/world/mujoco_handles.h"

namespace twin {
namespace {

// The section's keys: its table in bench/io/scenario_keys.cc (the scenario schema's source).
const YamlKeys kHandclaspKeys = ScenarioKeyNames("handclasp");

// Plausibility limits of the section (header): point count and distance, operator error, the
// told layout and tips (the twin's own limits, sim/world/twin_spec.cc).
constexpr std::size_t kMaxPoints = 100;        // Gan et al. teach 4-8; 100 is hours of jogging
constexpr double kMaxPointDistanceM = 5.0;     // the arms reach 1-4 m from their bases
constexpr double kMaxOperatorErrorM = 0.01;    // a 10 mm miss is no contact
constexpr double kMaxToldBaseDistanceM = 20.0;
constexpr double kMaxToldTipOffsetM = 1.0;

// A non-negative operator error in mm within kMaxOperatorErrorM.
double OperatorError(const YamlReader& r, const YamlField& f) {
  const double v = r.Number(f);
  if (v < 0) r.Fail(f, "must be >= 0 mm");
  if (v > 1e3 * kMaxOperatorErrorM) {
    r.Fail(f, "must be at most " + std::to_string(int(1e3 * kMaxOperatorErrorM)) +
                  " mm (an operator who misses by more has not made a contact), got " +
                  DescribeNode(f.node));
  }
  return 1e-3 * v;
}

// Coupled-motion path of robot 1's tip: offsets from the first contact point in B1 [m], a
// 50 mm square and a rise, so that the deviation is sampled along all three axes.
const Vector3 kCoupledPath[] = {{0, 0, 0},        {0.05, 0, 0}, {0.05, 0.05, 0},
                                {0, 0.05, 0.05}, {0, 0, 0.05}};
constexpr double kCoupledStandoff = 0.05;  // robot 2 approaches from here along its tip [m]

Transform TrueX_B1B2(const TwinTruth& truth) { return truth.X_WB[0].inverse() * truth.X_WB[1]; }

// The coupled-motion check (issue item 6, after the paper's cooperative motion): robot 1's tip
// follows a short path by its pendant IK; robot 2 is commanded through the estimated X_B1B2 to
// face it, by its pendant IK; the true tip-to-tip distance is measured after each pair of moves.
CoupledMotionResult CoupledMotion(BenchCell& cell,
                                  const std::array<KinematicModel, 2>& tip_models,
                                  const HandclaspContact& start,
                                  const Transform& X_B1B2_estimate) {
  CoupledMotionResult out;
  const auto fail = [&](const std::string& why) {
    out.reason = why;
    return out;
  };
  const Transform X_B1Tip1 = EndPose(tip_models[0], start.q1);
  const Matrix3 R_B2Tip2 = EndPose(tip_models[1], start.q2).linear();  // as at the contact
  const Transform X_B2B1 = X_B1B2_estimate.inverse();
  IkOptions ik;
  JointVector q1 = start.q1, q2 = start.q2;
  double worst = 0.0;
  std::vector<double> deviations;
  bool first = true;
  for (const Vector3& offset : kCoupledPath) {
    const Vector3 p_B1 = X_B1Tip1.translation() + offset;
    Transform target1 = X_B1Tip1;
    target1.translation() = p_B1;
    const IkResult r1 = SolveIk(tip_models[0], target1, q1, ik);
    if (r1.status != IkStatus::kSuccess) return fail("robot 1 path IK: " + r1.reason);
    q1 = r1.q;
    const MoveResult m1 = cell.MoveTo(0, q1);
    if (m1.status != MoveStatus::kSettled) return fail("robot 1 move: " + m1.reason);
    Transform target2 = Transform::Identity();
    target2.linear() = R_B2Tip2;
    target2.translation() = X_B2B1 * p_B1;
    if (first) {  // approach from a stand-off behind robot 2's tip, as the operator did
      Transform standoff = target2;
      standoff.translation() -= kCoupledStandoff * R_B2Tip2.col(2);
      const IkResult rs = SolveIk(tip_models[1], standoff, q2, ik);
      if (rs.status != IkStatus::kSuccess) return fail("robot 2 stand-off IK: " + rs.reason);
      const MoveResult ms = cell.MoveTo(1, rs.q);
      if (ms.status != MoveStatus::kSettled) return fail("robot 2 stand-off move: " + ms.reason);
      q2 = rs.q;
      first = false;
    }
    const IkResult r2 = SolveIk(tip_models[1], target2, q2, ik);
    if (r2.status != IkStatus::kSuccess) return fail("robot 2 follow IK: " + r2.reason);
    q2 = r2.q;
    const MoveResult m2 = cell.MoveTo(1, q2);
    if (m2.status != MoveStatus::kSettled) return fail("robot 2 follow move: " + m2.reason);
    const TwinTruth truth = cell.Truth();  // scoring only
    const double d = 1e3 * (truth.p_WTip[0] - truth.p_WTip[1]).norm();
    deviations.push_back(d);
    worst = std::max(worst, d);
  }
  out.ok = true;
  out.deviation_mm = deviations;
  out.max_deviation_mm = worst;
  return out;
}

// A tip model with its tip moved by dt_F in the flange frame.
KinematicModel WithTipCorrection(KinematicModel tip_model, const Vector3& dt_F) {
  tip_model.X_LtE.translation() += dt_F;
  return tip_model;
}

// Truth-only diagnostic: how far a controller's pendant tip model is from the true tip, in
// the scoring frame B' (X_BBp), over 200 seeded random joint configurations. The handclasp
// can be no better than these errors.
PendantTipError MeasurePendantTipError(const KinematicModel& true_tip,
                                      const KinematicModel& tip_model, const Transform& X_BBp) {
  constexpr int kConfigurations = 200;
  double sum2 = 0.0, worst = 0.0;
  for (const JointVector& q :
       RandomJointConfigurations(tip_model, kConfigurations, 1, DegToRad(10.0))) {
    const double e = 1e3 * (X_BBp * EndPose(tip_model, q).translation() -
                            EndPose(true_tip, q).translation())
                               .norm();
    sum2 += e * e;
    worst = std::max(worst, e);
  }
  PendantTipError out;
  out.rms_mm = std::sqrt(sum2 / kConfigurations);
  out.max_mm = worst;
  out.configurations = kConfigurations;
  return out;
}

}  // namespace

Transform KinematicBaseOffset(const KinematicModel& true_model,
                              const KinematicModel& pendant_model) {
  DhParameters delta;  // RotZ(dtheta1) TransZ(dd1): eq. 2 with a = alpha = beta = 0
  delta.theta_offset = true_model.links[0].dh.theta_offset - pendant_model.links[0].dh.theta_offset;
  delta.d = true_model.links[0].dh.d - pendant_model.links[0].dh.d;
  return true_model.X_BL0 * LinkTransform(delta, 0.0) * true_model.X_BL0.inverse();
}

Transform BestFitBaseOffset(const KinematicModel& true_tip_model,
                            const KinematicModel& pendant_tip_model, const Vector3& dt_F,
                            int configurations) {
  const KinematicModel model = WithTipCorrection(pendant_tip_model, dt_F);
  const std::vector<JointVector> qs =
      RandomJointConfigurations(model, configurations, 1, DegToRad(10.0));
  Eigen::Matrix3Xd a(3, qs.size()), b(3, qs.size());
  for (size_t c = 0; c < qs.size(); ++c) {
    a.col(c) = EndPose(model, qs[c]).translation();
    b.col(c) = EndPose(true_tip_model, qs[c]).translation();
  }
  Transform X = Transform::Identity();
  X.matrix() = Eigen::umeyama(a, b, false);  // b = X a: model frame B' to base B
  return X;
}

Transform KinematicFrameTruth(const TwinTruth& truth,
                              const std::array<KinematicModel, 2>& pendant_models) {
  const Transform X_B1B1p = KinematicBaseOffset(truth.models[0], pendant_models[0]);
  const Transform X_B2B2p = KinematicBaseOffset(truth.models[1], pendant_models[1]);
  return X_B1B1p.inverse() * TrueX_B1B2(truth) * X_B2B2p;
}

BaseConstraint ImpliedConstraint(const TwinSpec& twin) {
  if (twin.robots[0].installation != Installation::kFloor) return BaseConstraint::kGeneral;
  switch (twin.robots[1].installation) {
    case Installation::kFloor: return BaseConstraint::kFloorFloor;
    case Installation::kWall: return BaseConstraint::kFloorWall;
    case Installation::kCeiling: return BaseConstraint::kFloorCeiling;
  }
  return BaseConstraint::kGeneral;
}

namespace {

// Throws InputError when the scenario has no handclasp section.
void RequireHandclaspSection(const Scenario& scenario) {
  if (!IsPresent(scenario.handclasp)) {
    throw InputError(scenario.path + " scenario.handclasp",
                     "missing: the handclasp needs a handclasp section with the told "
                     "rough_base_from_robot1 and tips (see scenarios/gan2014_floor_floor.yaml)");
  }
  RequireTwoRobots(scenario, "handclasp", "the handclasp");
}

// Told values: from this section only, never from the twin's truth.
void ReadToldLayoutAndTips(const YamlReader& r, const YamlMap& m, const Scenario& scenario,
                           HandclaspConfig* c) {
  c->rough_X_B1B2 = ReadPoseWithin(r, m.Get("rough_base_from_robot1"), kMaxToldBaseDistanceM,
                                   "two arms that touch each other stand within a few metres");
  const YamlField tips = m.Get("tips");
  const YamlMap t(r, tips, scenario.robot_names);
  for (int k = 0; k < 2; ++k) {
    const std::optional<YamlField> tip = t.Find(scenario.robot_names[k], false);
    if (!tip) {
      r.Fail(tips, "missing the told tip of robot '" + scenario.robot_names[k] +
                       "' ({xyz_mm: [..], rpy_deg: [..]}, its frame in the flange by drawing)");
    }
    c->told_X_FTip[k] = ReadPoseWithin(r, *tip, kMaxToldTipOffsetM,
                                       "a measuring tip is shorter than a metre");
  }
}

// points: 'auto' (the default) or 4..kMaxPoints contact points in mm, each within
// kMaxPointDistanceM of robot 1's base.
void ReadContactPoints(const YamlReader& r, const YamlMap& m, HandclaspConfig* c) {
  if (const auto f = m.Find("points", false)) {
    if (f->node.IsScalar()) {
      if (r.String(*f) != "auto") r.Fail(*f, "must be 'auto' or a list of [x, y, z] points in mm");
    } else if (f->node.IsSequence()) {
      c->auto_points = false;
      if (f->node.size() < 4) {
        r.Fail(*f, "needs at least 4 contact points (paper section 3), got " +
                       std::to_string(f->node.size()));
      }
      if (f->node.size() > kMaxPoints) {
        r.Fail(*f, "at most " + std::to_string(kMaxPoints) + " contact points (the paper teaches "
                   "4 to 8; each is a jogged contact), got " + std::to_string(f->node.size()));
      }
      for (std::size_t i = 0; i < f->node.size(); ++i) {
        const Vector3 p = 1e-3 * r.Vector(f->Item(i));
        if (p.norm() > kMaxPointDistanceM) {
          r.Fail(f->Item(i), "a contact point must lie within 5000 mm of robot 1's base (the arms "
                             "reach 1-4 m), got " + std::to_string(1e3 * p.norm()) + " mm");
        }
        c->points_B1.push_back(p);
      }
    } else {
      r.Fail(*f, "must be 'auto' or a list of [x, y, z] points in mm, got " + DescribeNode(f->node));
    }
  }
}

// constraint: auto (keeps the implied one) or a named BaseConstraint.
void ReadConstraint(const YamlReader& r, const YamlMap& m, HandclaspConfig* c) {
  if (const auto f = m.Find("constraint", false)) {
    const std::string v = r.String(*f);
    if (v == "auto") {
    } else if (v == "general") {
      c->constraint = BaseConstraint::kGeneral;
    } else if (v == "floor_floor") {
      c->constraint = BaseConstraint::kFloorFloor;
    } else if (v == "floor_wall") {
      c->constraint = BaseConstraint::kFloorWall;
    } else if (v == "floor_ceiling") {
      c->constraint = BaseConstraint::kFloorCeiling;
    } else {
      r.Fail(*f, "must be one of auto, general, floor_floor, floor_wall, floor_ceiling; got '" +
                     v + "'");
    }
  }
}

// trials, coupled_motion and the workflow's calibrated-stage keys.
void ReadRunOptions(const YamlReader& r, const YamlMap& m, HandclaspConfig* c) {
  if (const auto f = m.Find("trials", false)) {
    c->trials = r.Integer(*f);
    if (c->trials < 1 || c->trials > 1000) r.Fail(*f, "must be in 1..1000");
  }
  if (const auto f = m.Find("coupled_motion", false)) c->coupled_motion = r.Bool(*f);
  if (const auto f = m.Find("calibrated_tip_identification", false)) {
    c->calibrated_tip_identification = r.Bool(*f);
  }
  if (const auto f = m.Find("calibrated_operator_error_mm", false)) {
    c->calibrated_operator_error_m = OperatorError(r, *f);
  }
}

}  // namespace

HandclaspConfig ParseHandclaspConfig(const Scenario& scenario) {
  HandclaspConfig c;
  c.constraint = ImpliedConstraint(scenario.twin);
  const YamlReader r(scenario.path);
  // The section must be there: its told values have no defaults.
  RequireHandclaspSection(scenario);
  const YamlMap m(r, scenario.handclasp, kHandclaspKeys);
  // The told layout and tips (required).
  ReadToldLayoutAndTips(r, m, scenario, &c);
  // The taught points, planned or listed.
  ReadContactPoints(r, m, &c);
  // The simulated operator's alignment error (truth side).
  if (const auto f = m.Find("operator_error_mm", false)) c.operator_error_m = OperatorError(r, *f);
  // The installation constraint, else the implied one.
  ReadConstraint(r, m, &c);
  // Batch size, coupled motion and the workflow's calibrated stage.
  ReadRunOptions(r, m, &c);
  return c;
}

TeachOptions HandclaspTeachOptions(const Scenario& scenario, bool identify_tips) {
  TeachOptions teach;
  teach.seed = scenario.seeds.estimator;
  if (identify_tips) teach.orientations_per_point = 4;
  return teach;
}

TaughtPoints TeachHandclaspPoints(const HandclaspConfig& config,
                                  const std::array<KinematicModel, 2>& pendant_models_flange,
                                  const std::array<JointVector, 2>& seeds,
                                  const TeachOptions& options) {
  // The pendants' tips are the told ones (by drawing), never the twin's true tips.
  std::array<KinematicModel, 2> tip_models;
  for (int k = 0; k < 2; ++k) {
    tip_models[k] = WithTipTool(pendant_models_flange[k], config.told_X_FTip[k]);
  }
  // The operator teaches from the cell layout as drawn (told), not from the truth.
  return config.auto_points
             ? PlanTaughtPoints(tip_models, config.rough_X_B1B2, seeds, options)
             : TeachPoints(tip_models, config.rough_X_B1B2, config.points_B1, seeds, options);
}

namespace {

// What a stage's steps read: the caller's inputs, the section and the pendants' tip models.
struct StageInputs {
  const Scenario& scenario;
  const std::array<KinematicModel, 2>& pendant_models_flange;  ///< the controllers' models
  const HandclaspStageOptions& options;
  HandclaspConfig config;                    ///< the section with the stage's overrides
  std::array<KinematicModel, 2> tip_models;  ///< pendant models with the told tips as tools
};

// Parses the section, applies the stage's operator error to the cell and builds the pendants'
// tip models.
StageInputs PrepareStage(BenchCell& cell, const Scenario& scenario,
                         const std::array<KinematicModel, 2>& pendant_models_flange,
                         const HandclaspStageOptions& stage_options, std::ostream& progress) {
  StageInputs in{scenario, pendant_models_flange, stage_options, ParseHandclaspConfig(scenario),
                 {}};
  HandclaspConfig& config = in.config;
  if (stage_options.operator_error_m) config.operator_error_m = *stage_options.operator_error_m;
  if (!cell.SetOperatorAlignmentError(config.operator_error_m)) {
    progress << "handclasp: the cell's operator is a person: operator_error is not simulated\n";
    config.operator_error_m = std::numeric_limits<double>::quiet_NaN();  // null in the report
  }
  // The pendants' tips are the told ones (by drawing), never the twin's true tips.
  for (int k = 0; k < 2; ++k) {
    in.tip_models[k] = WithTipTool(pendant_models_flange[k], config.told_X_FTip[k]);
  }
  return in;
}

// The teaching options used and the points taught.
struct Teaching {
  TeachOptions teach;
  TaughtPoints taught;
};

// Plans or teaches the contact points from the current encoders.
Teaching TeachContactPoints(BenchCell& cell, const StageInputs& in) {
  const std::array<JointVector, 2> seeds = {cell.ReadEncoders(0), cell.ReadEncoders(1)};
  Teaching t;
  t.teach = HandclaspTeachOptions(in.scenario, in.options.identify_tips);
  t.taught = TeachHandclaspPoints(in.config, in.pendant_models_flange, seeds, t.teach);
  return t;
}

// The stage's record of the teaching: the section's constraint and operator, the points.
HandclaspTeaching TeachingRecord(const HandclaspConfig& config, const Teaching& t) {
  HandclaspTeaching r;
  r.installation = config.constraint;
  r.operator_error_m = config.operator_error_m;
  r.planned = config.auto_points;
  r.orientations_per_point = t.teach.orientations_per_point;
  r.taught = t.taught;
  return r;
}

// Runs calib's procedure on the taught joint angles with the section's constraint.
HandclaspResult RunProcedure(BenchCell& cell, const StageInputs& in, const TaughtPoints& taught,
                             std::ostream& progress) {
  HandclaspOptions options;
  options.constraint = in.config.constraint;
  options.identify_tips = in.options.identify_tips;
  return RunHandclaspProcedure(cell, in.tip_models, taught.q1, options, &progress);
}

// The truth the estimates are scored against, and the tip corrections used.
struct ScoringFrames {
  TwinTruth twin_truth;                        ///< cell.Truth() after the procedure
  bool tips_ok = false;                        ///< the procedure identified the tips
  std::array<Vector3, 2> dt;                   ///< identified tip corrections, else zero [m]
  std::array<KinematicModel, 2> true_tips;     ///< true models with the true tips
  std::array<Transform, 2> X_BBp;              ///< scoring frames B' in B
  Transform physical = Transform::Identity();  ///< true X_B1B2
  Transform truth = Transform::Identity();     ///< X_B1'B2': what the estimates are scored against
};

// Scored against the frames the pendant models use (KinematicFrameTruth: link 1's theta and
// d errors are invisible to any kinematic calibration; BestFitBaseOffset for calibrated
// models); the physical transform is scored too, under physical_truth, so that nothing is
// hidden.
ScoringFrames ComputeScoringFrames(const TwinTruth& twin_truth, const StageInputs& in,
                                   const HandclaspResult& result) {
  ScoringFrames s;
  s.twin_truth = twin_truth;
  s.tips_ok = result.ok() && result.tips.ok;
  s.dt = {s.tips_ok ? result.tips.dt1_F1 : Vector3::Zero(),
          s.tips_ok ? result.tips.dt2_F2 : Vector3::Zero()};
  for (int k = 0; k < 2; ++k) {
    s.true_tips[k] = WithTipTool(s.twin_truth.models[k], s.twin_truth.X_FTip[k]);
    s.X_BBp[k] = in.options.best_fit_frames
                     ? BestFitBaseOffset(s.true_tips[k], in.tip_models[k], s.dt[k])
                     : KinematicBaseOffset(s.twin_truth.models[k], in.pendant_models_flange[k]);
  }
  s.physical = TrueX_B1B2(s.twin_truth);
  s.truth = s.X_BBp[0].inverse() * s.physical * s.X_BBp[1];
  return s;
}

// The frames the estimates are scored in, the link-1 offsets and the pendant tips' errors
// there (truth only).
HandclaspScoringFrames ScoringFramesRecord(const ScoringFrames& s, const StageInputs& in) {
  HandclaspScoringFrames f;
  f.best_fit = in.options.best_fit_frames;
  f.truth = s.truth;
  f.physical = s.physical;
  f.X_BBp = s.X_BBp;
  for (int k = 0; k < 2; ++k) {
    const DhParameters& t = s.twin_truth.models[k].links[0].dh;
    const DhParameters& m = in.pendant_models_flange[k].links[0].dh;
    f.dtheta1_rad[k] = t.theta_offset - m.theta_offset;
    f.dd1_m[k] = t.d - m.d;
    f.pendant_tip_error[k] = MeasurePendantTipError(
        s.true_tips[k], WithTipCorrection(in.tip_models[k], s.dt[k]), s.X_BBp[k]);
  }
  return f;
}

// An estimate scored against the kinematic-frame truth and the physical X_B1B2.
// Without frames (a cell without truth) the errors are NaN, null in the report.
ScoredBaseFrame ScoreEstimate(const Transform& X, const ScoringFrames* s) {
  ScoredBaseFrame f;
  f.present = true;
  if (!s) {
    constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
    f.kinematic = f.physical = {kNone, kNone};
    return f;
  }
  f.kinematic = CompareBaseFrames(X, s->truth);  // eq. 33-34
  f.physical = CompareBaseFrames(X, s->physical);
  return f;
}

// Marks the stage ok and scores the general and constrained estimates into out.
void ScoreEstimates(const BaseCalibrationResult& cal, const ScoringFrames* s,
                    HandclaspStageResult* out) {
  out->status = HandclaspStageStatus::kOk;
  out->X_B1B2_general = cal.X_B1B2_general;
  out->X_B1B2_constrained = cal.X_B1B2_constrained;
  out->general = ScoreEstimate(cal.X_B1B2_general, s);
  out->constrained = ScoreEstimate(cal.X_B1B2_constrained, s);
}

// When the tips were identified, the estimate with the tips scored into out.
void ScoreIdentifiedTips(const TipRefinementResult& tips, const ScoringFrames* s,
                         HandclaspStageResult* out) {
  if (!tips.ok) return;
  out->tips = ScoreEstimate(tips.X_B1B2, s);
  out->X_B1B2_tips = tips.X_B1B2;
}

// The coupled-motion check with the delivered estimate, into out.
void RunCoupledMotionCheck(BenchCell& cell, const StageInputs& in, const HandclaspResult& result,
                           HandclaspStageResult* out) {
  // With identified tips the controllers use them (the TCP a pendant would store).
  const bool tips_ok = result.ok() && result.tips.ok;
  std::array<KinematicModel, 2> used = in.tip_models;
  if (tips_ok) {
    used[0] = WithTipCorrection(in.tip_models[0], result.tips.dt1_F1);
    used[1] = WithTipCorrection(in.tip_models[1], result.tips.dt2_F2);
  }
  CoupledMotionResult check =
      CoupledMotion(cell, used, result.contacts.front(),
                    tips_ok ? result.tips.X_B1B2 : result.calibration.X_B1B2_constrained);
  check.estimate = tips_ok ? "tips_identified" : "constrained";
  if (check.ok) out->coupled_motion_max_deviation_mm = check.max_deviation_mm;
  out->coupled_motion = std::move(check);
}

// Marks the stage failed because no points could be taught, and prints why.
void ReportTeachingFailure(const TaughtPoints& taught, std::ostream& progress,
                           HandclaspStageResult* out) {
  out->status = HandclaspStageStatus::kTeachingFailed;
  out->reason = "teaching: " + taught.reason;
  progress << "handclasp: teaching failed: " << taught.reason << "\n";
}

// Marks the stage failed with the procedure's reason, and prints it.
void ReportProcedureFailure(const HandclaspResult& result, std::ostream& progress,
                            HandclaspStageResult* out) {
  out->status = HandclaspStageStatus::kProcedureFailed;
  out->reason = result.reason;
  progress << "handclasp: " << result.reason << "\n";
}

// The closing progress line: both estimates' errors in the kinematic frames.
void PrintStageSummary(BaseConstraint constraint, const HandclaspStageResult& out,
                       std::ostream& progress) {
  progress << "handclasp: " << ToString(constraint) << " general e_tran "
           << out.general.kinematic.e_tran_mm << " mm, e_rot " << out.general.kinematic.e_rot_deg
           << " deg; constrained e_tran " << out.constrained.kinematic.e_tran_mm << " mm, e_rot "
           << out.constrained.kinematic.e_rot_deg << " deg\n";
}

// On a cell without truth (a real cell) the coupled-motion check is skipped: it drives robot
// 2's tip onto robot 1's through an estimate nothing has checked, and nothing would measure it.
void SkipCoupledMotionCheck(HandclaspStageResult* out) {
  CoupledMotionResult skipped;
  skipped.skipped = "the cell offers no truth: robot 2's tip is not driven onto robot 1's "
                    "through an unchecked estimate, and nothing would measure the distance";
  skipped.max_deviation_mm = std::numeric_limits<double>::quiet_NaN();
  skipped.estimate = out->delivered_name();
  out->coupled_motion = std::move(skipped);
}

}  // namespace

HandclaspStageResult RunHandclaspStage(BenchCell& cell, const Scenario& scenario,
                                       const std::array<KinematicModel, 2>& pendant_models_flange,
                                       std::ostream& progress,
                                       const HandclaspStageOptions& stage_options) {
  // The section, the operator's error on the cell and the pendants' told tip models.
  const StageInputs in =
      PrepareStage(cell, scenario, pendant_models_flange, stage_options, progress);
  // The operator's taught points, planned from the told layout.
  const Teaching teaching = TeachContactPoints(cell, in);
  HandclaspStageResult out;
  out.teaching = TeachingRecord(in.config, teaching);
  out.tips_attempted = stage_options.identify_tips;
  if (!teaching.taught.ok) {
    ReportTeachingFailure(teaching.taught, progress, &out);
    return out;
  }
  // The contacts and the calibration, through the Cell interface only.
  out.procedure = RunProcedure(cell, in, teaching.taught, progress);
  const HandclaspResult& result = out.procedure;
  // --- the procedure has ended: scoring against the truth from here on (a cell without truth,
  // a real one: the estimates alone, their errors NaN) ---
  out.truth_available = cell.HasTruth();
  std::optional<ScoringFrames> frames;
  if (out.truth_available) {
    frames = ComputeScoringFrames(cell.Truth(), in, result);
    out.frames = ScoringFramesRecord(*frames, in);
  }
  if (!result.ok()) {
    ReportProcedureFailure(result, progress, &out);
    return out;
  }
  // The general and constrained estimates (eq. 33-34).
  const ScoringFrames* scoring = frames ? &*frames : nullptr;
  ScoreEstimates(result.calibration, scoring, &out);
  if (stage_options.identify_tips) ScoreIdentifiedTips(result.tips, scoring, &out);
  if (!out.truth_available) {
    if (in.config.coupled_motion) SkipCoupledMotionCheck(&out);
    progress << "handclasp: " << ToString(in.config.constraint)
             << " estimated (the cell offers no truth to score against)\n";
    return out;
  }
  if (in.config.coupled_motion) RunCoupledMotionCheck(cell, in, result, &out);
  PrintStageSummary(in.config.constraint, out, progress);
  return out;
}

HandclaspStageResult RunHandclaspStage(TwinCell& cell, const Scenario& scenario,
                                       const std::array<KinematicModel, 2>& pendant_models_flange,
                                       std::ostream& progress,
                                       const HandclaspStageOptions& stage_options) {
  LocalTwinCell bench_cell(cell);
  return RunHandclaspStage(bench_cell, scenario, pendant_models_flange, progress, stage_options);
}

namespace {

// A loaded scenario with its trial applied and its sections parsed.
struct HandclaspRunInputs {
  Scenario scenario;
  HandclaspConfig config;
  Acceptance acceptance;
};

// Whether the run's cell is other than the scenario's twin in this process.
bool DrivesAnotherCell(const CellOptions& cell) {
  return !cell.address.empty() || !cell.record_dir.empty() || !cell.replay_dir.empty();
}

// Everything is validated before anything runs or is written
// (docs/reference/exit-codes-and-safety.md).
HandclaspRunInputs LoadAndValidate(const RunOptions& o, std::string* text) {
  Scenario scenario = LoadRunScenario(o, text);
  HandclaspConfig config = ParseHandclaspConfig(scenario);
  if (DrivesAnotherCell(o.cell) && config.trials != 1) {
    throw InputError(scenario.path + " scenario.handclasp.trials",
                     "a run on a served, recorded or replayed cell runs one trial on that one "
                     "cell; trials must be 1, got " + std::to_string(config.trials) +
                         " (serve each trial with `serve-cell --trial N` and run it with "
                         "`run --trial N`)");
  }
  Acceptance acceptance = ParseAcceptance(scenario);
  ValidateOutputFolder(o.out_dir, "--out");
  if (!o.junit.empty()) ValidateJunitFile(o.junit, o.out_dir);
  return {std::move(scenario), std::move(config), std::move(acceptance)};
}

// Runs every trial of the batch on a fresh twin with seed twin.seed + t and the nominal
// models, or its one trial on the cell `cell_options` names; throws InputError when a
// trial's procedure refused.
HandclaspBatchResult RunTrials(const Scenario& scenario, const HandclaspConfig& config,
                               const CellOptions& cell_options, std::ostream& progress) {
  const std::array<KinematicModel, 2> nominal = {scenario.twin.robots[0].model,
                                                 scenario.twin.robots[1].model};
  HandclaspBatchResult b;
  b.trials = config.trials;
  for (int t = 0; t < config.trials; ++t) {
    TwinSpec spec = scenario.twin;
    spec.seed = scenario.twin.seed + static_cast<std::uint64_t>(t);
    progress << "handclasp: trial " << t + 1 << "/" << config.trials << " (seed " << spec.seed
             << ")\n";
    const std::unique_ptr<BenchCell> cell = OpenBenchCell(spec, scenario.path, cell_options);
    HandclaspStageResult stage = RunHandclaspStage(*cell, scenario, nominal, progress);
    cell->Finish();  // the last call: a recording is complete, a replay used up
    if (stage.truth_available) stage.seed = spec.seed;  // a real cell has no seed
    if (!stage.ok()) {
      // A refused procedure is exit 2 with its reason (docs/reference/exit-codes-and-safety.md);
      // nothing is written.
      ++b.failures;
      throw InputError(scenario.path + " scenario.handclasp",
                       "the handclasp procedure refused in trial " + std::to_string(t + 1) + "/" +
                           std::to_string(config.trials) + " (seed " + std::to_string(spec.seed) +
                           "): " + stage.reason);
    }
    b.done.push_back(std::move(stage));
  }
  return b;
}

// Writes out_dir/report.json through a staging folder renamed onto out_dir when complete.
void PublishReport(const std::string& report_text, const std::string& out_dir) {
  const std::string staging = CreateStagingDirectory(out_dir);
  try {
    {
      std::ofstream f(std::filesystem::path(staging) / "report.json");
      f << report_text;
      if (!f) throw InputError(out_dir + "/report.json", "writing the report failed");
    }
    PublishDirectory(staging, out_dir);
  } catch (...) {
    DiscardStaging(staging);
    throw;
  }
}

}  // namespace

namespace {

int RunHandclasp(const RunOptions& o, std::ostream& progress) {
  const std::string& out_dir = o.out_dir;
  const std::string& junit = o.junit;
  const auto t_start = std::chrono::steady_clock::now();
  // The scenario, its handclasp and acceptance sections and the output paths, all checked.
  std::string text;
  const HandclaspRunInputs in = LoadAndValidate(o, &text);
  InstallMujocoErrorHandlers();
  // Each trial's handclasp stage on its own twin (or the one trial on the cell named; on a cell
  // without truth, a real one, the estimates alone).
  const HandclaspBatchResult batch =
      RunTrials(in.scenario, in.config, RunCellOptions(o, in.scenario, text), progress);
  // report.json with the acceptance criteria judged on it; without truth, those on figures
  // against it are left out, and said so.
  const bool scored = batch.done.empty() || batch.done.front().truth_available;
  AcceptanceVerdict verdict;
  const std::string report = HandclaspReportText(
      in.scenario, batch, scored ? in.acceptance : WithoutTruthCriteria(in.acceptance, false),
      &verdict);
  PublishReport(report, out_dir);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  if (!junit.empty()) WriteJunit(junit, in.scenario.name, verdict, seconds);
  PrintVerdict(verdict, progress);
  return VerdictExitCode(verdict);
}

}  // namespace

int RunHandclaspScenario(const RunOptions& options) { return RunHandclasp(options, std::cerr); }

int RunHandclaspScenario(const std::string& scenario_path, const std::string& out_dir,
                         std::ostream& progress, int trial, const std::string& junit) {
  RunOptions o;
  o.scenario = scenario_path;
  o.out_dir = out_dir;
  o.trial = trial;
  o.junit = junit;
  return RunHandclasp(o, progress);
}

int RunHandclaspScenario(const std::string& scenario_path, const std::string& out_dir) {
  return RunHandclaspScenario(scenario_path, out_dir, std::cerr, 0, "");
}

}  // namespace twin
