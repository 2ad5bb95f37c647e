#include "calib/procedures/optical_axis_procedure.h"

#include <algorithm>
#include <atomic>
#include <future>
#include <map>
#include <memory>
#include <cmath>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>

#include <opencv2/calib3d.hpp>

#include "calib/cell/cell_moves.h"
#include "calib/common/clock.h"
#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "calib/kinematics/inverse_kinematics.h"
#include "calib/vision/axis_start_predictor.h"
#include "calib/vision/board_pose.h"
#include "calib/vision/board_region.h"

namespace twin {
namespace {

std::string Fixed(double v, int digits) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(digits);
  os << v;
  return os.str();
}

std::string Sci(double v) {
  std::ostringstream os;
  os.precision(2);
  os << v;
  return os.str();
}

// The samples of `axes` (plan indices), renumbered 0.. in that order; axes with fewer than 3
// samples are dropped (and left out of `kept`).
std::vector<AxisSample> Subset(const std::vector<AxisSample>& samples, const std::vector<int>& axes,
                               std::vector<int>* kept = nullptr) {
  std::vector<AxisSample> out;
  int next = 0;
  for (int k : axes) {
    std::vector<AxisSample> these;
    for (const AxisSample& s : samples) {
      if (s.axis == k) these.push_back(s);
    }
    if (these.size() < 3) continue;
    for (AxisSample& s : these) {
      s.axis = next;
      out.push_back(s);
    }
    if (kept) kept->push_back(k);
    ++next;
  }
  return out;
}

MisalignedSummary Misaligned(const KinematicModel& before, const KinematicModel& after,
                             const std::vector<AxisSample>& samples) {
  MisalignedSummary m;
  m.samples = static_cast<int>(samples.size());
  if (samples.empty()) return m;
  m.before = MeanMisalignedErrorNorm(before, samples);
  m.after = MeanMisalignedErrorNorm(after, samples);
  return m;
}

// A plan and where it came from.
struct PlanOutcome {
  PosePlanResult plan;
  bool from_store = false;
  double seconds = 0;  // wall time of the lookup and the planning
};

// The plan of `inputs`: from the store when it has it, else planned (and kept there).
PlanOutcome PlanWithStore(PlanInputs inputs, std::shared_ptr<PlanStore> store,
                          std::shared_ptr<std::atomic<bool>> cancel) {
  const auto t0 = Clock::now();
  PlanOutcome out;
  std::optional<PosePlanResult> stored;
  if (store) stored = store->Find(inputs);
  if (stored) {
    out.plan = std::move(*stored);
    out.from_store = true;
  } else {
    PosePlannerOptions o = inputs.options;
    o.cancel = cancel;
    try {
      out.plan = PlanCalibrationPoses(inputs.active, inputs.passive, inputs.X_BaBp, inputs.X_FC, o);
    } catch (...) {
      if (store) store->Abandon(inputs);
      throw;
    }
    if (store) {
      if (out.plan.status == PosePlannerStatus::kSuccess) {
        store->Store(inputs, out.plan);
      } else {
        store->Abandon(inputs);
      }
    }
  }
  out.seconds = SecondsSince(t0);
  return out;
}

}  // namespace

void ValidateOpticalAxisOptions(const OpticalAxisOptions& o) {
  // The scenario's calibration keys are checked where they are read (robots by name, once
  // each; intrinsics_views 3 to 500; board_pose_test_p 0 to 0.5) and no user sets the others:
  // a bad value is our bug. calibration_axes is the exception (its key is unbounded there).
  const std::string where = "OpticalAxisOptions";
  TWIN_REQUIRE(o.linearized_max_pairs >= 0,
               "linearized_max_pairs must be >= 0, got " + std::to_string(o.linearized_max_pairs));
  TWIN_REQUIRE(!o.robots.empty() && o.robots.size() <= 2,
               "expected one or two robots to calibrate, got " + std::to_string(o.robots.size()));
  std::set<int> seen;
  for (int r : o.robots) {
    TWIN_REQUIRE(r == 0 || r == 1, "robot index " + std::to_string(r) + " is not 0 or 1");
    TWIN_REQUIRE(seen.insert(r).second, "robot " + std::to_string(r) + " listed twice");
  }
  TWIN_REQUIRE(o.intrinsics_views >= 3,
               "intrinsics_views = " + std::to_string(o.intrinsics_views) + ": expected >= 3");
  ValidateIntrinsicsOptions(o.intrinsics);
  ValidatePosePlannerOptions(o.planner);
  ValidateServoOptions(o.servo);
  ValidateLinearizedIdentificationOptions(o.linearized);
  ValidateNonlinearIdentificationOptions(o.nonlinear);
  TWIN_REQUIRE(o.board_pose_test_p >= 0 && o.board_pose_test_p < 1,
               "board_pose_test_p = " + Sci(o.board_pose_test_p) +
                   ": expected a p-value in [0, 1) (0: no test)");
  if (o.calibration_axes < 1 || o.calibration_axes > o.planner.num_axes) {
    throw InputError(where + ".calibration_axes",
                     std::to_string(o.calibration_axes) + ": expected 1 .. num_axes (" +
                         std::to_string(o.planner.num_axes) +
                         ") (calibration.calibration_axes, calibration.planning.axes)");
  }
  TWIN_REQUIRE(o.kept_images >= 0,
               "kept_images = " + std::to_string(o.kept_images) + ": expected >= 0");
}

KinematicModel BoardRobotModel(const KinematicModel& nominal, const Transform& X_FT) {
  KinematicModel m = nominal;
  // The mount's translation becomes link 7's eq. 2 parameters (theta = atan2(y, x), d = z,
  // a = the distance from the flange axis) and its rotation stays in X_LtE, so that link 7's
  // a, theta and d move the feature point radially, tangentially and along z to first order
  // wherever it sits. With the whole mount in X_LtE (identity link 7), a point on the flange
  // plane's y axis had no first-order parameter along y: exact synthetic data with depths
  // stopped at 0.05 mm (tests/bench/calibration_cli_test.cc).
  const Vector3 p = X_FT.translation();
  DhParameters dh;
  const double radial = std::hypot(p.x(), p.y());
  dh.theta_offset = radial > 1e-9 ? std::atan2(p.y(), p.x()) : 0.0;
  dh.d = p.z();
  dh.a = radial;
  m.tool().dh = dh;
  m.tool().inertia = LinkInertia{};
  m.X_LtE = LinkTransform(dh, 0.0).inverse() * X_FT;  // L7 X_LtE = X_FT exactly
  return m;
}

namespace {

// The smallest identifiable singular value of the identification of `samples` at the nominal
// model (Ceres formulation, scale measurement included when recorded; the first pass's
// Jacobian, no solve: the split compares the plans' geometry; one Jacobian per subset instead
// of a full identification per subset took the paper scenario's identification stage from
// 16.5 s to 0.8 s per trial, README.md of e5af83d, "Speed of trials"); 0 when nothing is
// identifiable. The identifiable rank and the smallest identifiable singular value of `samples` at
// `model`.
std::pair<int, double> IdentifiableRankAndSmallest(const KinematicModel& model,
                                                   const std::vector<AxisSample>& samples,
                                                   const NonlinearIdentificationOptions& options) {
  const ObservabilityReport o = NonlinearIdentifiability(model, samples, options);
  if (o.rank < 1 || static_cast<int>(o.singular_values.size()) < o.rank) return {0, 0.0};
  return {o.rank, o.singular_values[o.rank - 1]};
}

}  // namespace

void SplitAxes(const KinematicModel& at, const std::vector<AxisSample>& samples,
               int num_axes, const OpticalAxisOptions& options, std::vector<int>* cal_axes,
               std::vector<int>* val_axes,
               std::vector<std::pair<std::vector<int>, double>>* candidates) {
  cal_axes->clear();
  val_axes->clear();
  candidates->clear();
  std::vector<int> usable;  // axes with 3 or more aligned poses
  for (int k = 0; k < num_axes; ++k) {
    std::vector<int> kept;
    Subset(samples, {k}, &kept);
    if (!kept.empty()) usable.push_back(k);
  }
  const int n = std::min<int>(options.calibration_axes, static_cast<int>(usable.size()));
  if (options.split == OpticalAxisOptions::Split::kFirst ||
      n >= static_cast<int>(usable.size()) || n < 1) {
    for (int k = 0; k < num_axes; ++k) {
      (k < options.calibration_axes ? *cal_axes : *val_axes).push_back(k);
    }
    return;
  }
  // Every n-subset of the usable axes (C(5, 3) = 10 for the paper's plan).
  std::vector<bool> pick(usable.size(), false);
  std::fill(pick.begin(), pick.begin() + n, true);
  // The highest identifiable rank first (a subset that leaves a direction unidentified must
  // not win by not counting it), then the largest smallest singular value.
  std::pair<int, double> best{-1, -1.0};
  do {
    std::vector<int> subset;
    for (size_t i = 0; i < usable.size(); ++i) {
      if (pick[i]) subset.push_back(usable[i]);
    }
    const std::pair<int, double> score =
        IdentifiableRankAndSmallest(at, Subset(samples, subset), options.nonlinear);
    candidates->emplace_back(subset, score.second);
    if (score > best) {
      best = score;
      *cal_axes = subset;
    }
  } while (std::prev_permutation(pick.begin(), pick.end()));
  for (int k = 0; k < num_axes; ++k) {
    if (std::find(cal_axes->begin(), cal_axes->end(), k) == cal_axes->end()) {
      val_axes->push_back(k);
    }
  }
}

namespace {

// The calibration and validation samples of one robot, and the plan axes they kept.
struct IdentificationSets {
  std::vector<int> cal_kept, val_kept;  // plan axes with 3 or more samples
  std::vector<AxisSample> cal, val;     // their samples, renumbered 0..
};

// Takes the samples of the split's axes (recorded in rc) and throws InputError when the
// calibration set cannot constrain the collinearity of at least 2 optical axes.
IdentificationSets SelectIdentificationSets(const std::vector<int>& calibration_axes,
                                            const std::vector<int>& validation_axes,
                                            RobotCalibration* rc) {
  IdentificationSets sets;
  std::vector<int>& cal_kept = sets.cal_kept;
  std::vector<int>& val_kept = sets.val_kept;
  sets.cal = Subset(rc->samples, calibration_axes, &cal_kept);
  sets.val = Subset(rc->samples, validation_axes, &val_kept);
  const std::vector<AxisSample>& cal = sets.cal;
  rc->calibration_axes = cal_kept;
  rc->validation_axes = val_kept;
  const std::string name = rc->nominal.name.empty() ? "robot " + std::to_string(rc->robot)
                                                    : rc->nominal.name;
  if (cal.empty()) {
    throw InputError(name + " identification",
                     "no calibration axis has 3 or more aligned poses; nothing to identify");
  }
  if (cal_kept.size() < 2) {
    // One line through the points of one axis fits any model that keeps them collinear: the
    // problem is rank-deficient far beyond the named combinations.
    throw InputError(name + " identification",
                     "only one calibration axis (plan axis " + std::to_string(cal_kept[0] + 1) +
                         ") has 3 or more aligned poses; the collinearity constraint needs at "
                         "least 2 optical axes (see the skipped poses and axes above)");
  }
  return sets;
}

// Eq. 45-49: the paper's recursive linearized LM on `cal`, or rc->linearized marked skipped
// when its pair stack (eq. 22) exceeds options.linearized_max_pairs.
void IdentifyLinearizedUnlessTooLarge(const std::vector<AxisSample>& cal,
                                      const OpticalAxisOptions& options, RobotCalibration* rc) {
  std::vector<long long> per_axis_count;
  for (const AxisSample& s : cal) {
    if (static_cast<int>(per_axis_count.size()) <= s.axis) per_axis_count.resize(s.axis + 1, 0);
    ++per_axis_count[s.axis];
  }
  long long pairs = 0;
  for (long long n : per_axis_count) pairs += n * (n - 1) / 2;
  if (pairs <= options.linearized_max_pairs) {
    rc->linearized = IdentifyFromOpticalAxes(rc->nominal, cal, options.linearized);
  } else {
    rc->linearized = LinearizedIdentificationResult{};
    rc->linearized.status = LinearizedIdentificationStatus::kSkipped;
    rc->linearized.reason = std::to_string(pairs) + " sample pairs exceed linearized_max_pairs = " +
                            std::to_string(options.linearized_max_pairs) +
                            " (eq. 22 is quadratic in the samples); the engine alone identifies";
    rc->linearized.model = rc->nominal;
    rc->linearized.correction = ParameterVector::Zero(rc->nominal.num_parameters());
  }
}

// Ceres with nuisance lines (and the scale measurement when depths were recorded) on `cal`;
// its model is identified unless it failed, then the linearized one is.
void IdentifyNonlinearOrFallBack(const std::vector<AxisSample>& cal,
                                 const OpticalAxisOptions& options, RobotCalibration* rc) {
  rc->nonlinear = IdentifyNonlinear(rc->nominal, cal, options.nonlinear);
  if (rc->nonlinear.status != NonlinearIdentificationStatus::kFailed) {
    rc->identified = rc->nonlinear.model;
    rc->method = rc->nonlinear.depth_used ? "ceres_with_scale" : "ceres";
  } else {
    rc->identified = rc->linearized.model;
    rc->method = "linearized";
  }
}

// The mean misaligned errors (eq. 46) of the identified model on both sets and on each plan
// axis.
void SummarizeMisalignedErrors(const IdentificationSets& sets, RobotCalibration* rc) {
  const std::vector<AxisSample>& cal = sets.cal;
  const std::vector<AxisSample>& val = sets.val;
  rc->calibration_error = Misaligned(rc->nominal, rc->identified, cal);
  rc->validation_error = Misaligned(rc->nominal, rc->identified, val);
  int num_axes = 0;
  for (const AxisSample& s : rc->samples) num_axes = std::max(num_axes, s.axis + 1);
  rc->per_axis.assign(num_axes, MisalignedSummary{});
  for (int k = 0; k < num_axes; ++k) {
    rc->per_axis[k] = Misaligned(rc->nominal, rc->identified, Subset(rc->samples, {k}));
  }
}

// The calibration-set model becomes the hold-out model, with the covariance of its Ceres
// solution (none for the linearized fallback).
void KeepHoldoutModel(const std::vector<AxisSample>& cal, RobotCalibration* rc) {
  rc->holdout = rc->identified;
  rc->refit = false;
  rc->covariance = IdentificationCovariance{};
  if (rc->method != "linearized") {
    rc->covariance = EstimateIdentificationCovariance(rc->nominal, cal, rc->nonlinear);
  }
}

// Ceres again on every kept axis; when it succeeds its model, covariance and method are
// delivered.
void RefitOnAllAxes(const IdentificationSets& sets, const OpticalAxisOptions& options,
                    RobotCalibration* rc) {
  const std::vector<int>& cal_kept = sets.cal_kept;
  const std::vector<int>& val_kept = sets.val_kept;
  std::vector<int> all = cal_kept;
  all.insert(all.end(), val_kept.begin(), val_kept.end());
  std::sort(all.begin(), all.end());
  const auto t1 = Clock::now();
  const std::vector<AxisSample> all_samples = Subset(rc->samples, all);
  NonlinearIdentificationResult f = IdentifyNonlinear(rc->nominal, all_samples, options.nonlinear);
  rc->identification_s += SecondsSince(t1);
  if (f.status != NonlinearIdentificationStatus::kFailed) {
    rc->covariance = EstimateIdentificationCovariance(rc->nominal, all_samples, f);
    rc->identified = f.model;
    rc->method = std::string(f.depth_used ? "ceres_with_scale" : "ceres") + "_all_axes";
    rc->refit_result = std::move(f);
    rc->refit = true;
  }
}

}  // namespace

void IdentifyRobot(const std::vector<int>& calibration_axes,
                   const std::vector<int>& validation_axes, const OpticalAxisOptions& options,
                   RobotCalibration* rc) {
  // The samples of each set; at least 2 calibration axes.
  const IdentificationSets sets = SelectIdentificationSets(calibration_axes, validation_axes, rc);
  const auto t0 = Clock::now();
  // Eq. 45-49: the paper's recursive linearized LM, when its pair stack stays reasonable.
  IdentifyLinearizedUnlessTooLarge(sets.cal, options, rc);
  // Ceres with nuisance lines (and the scale measurement when depths were recorded).
  IdentifyNonlinearOrFallBack(sets.cal, options, rc);
  rc->identification_s += SecondsSince(t0);
  // Misaligned errors (eq. 46) before and after, per set and per axis.
  SummarizeMisalignedErrors(sets, rc);
  // The calibration-set model and its covariance, as validated.
  KeepHoldoutModel(sets.cal, rc);
  // The delivered model refitted on all axes after the hold-out validation.
  if (options.refit_all_axes && !sets.val_kept.empty()) RefitOnAllAxes(sets, options, rc);
}

namespace {

// What every stage of the procedure reads: the cell, the estimator's knowledge, the options
// and the joint angles the cell started at.
struct ProcedureContext {
  Cell& cell;
  const CellKnowledge& knowledge;
  const OpticalAxisOptions& options;
  std::array<JointVector, 2> home;  // where the cell starts: the camera sees the board

  // Passes one progress line to options.progress, if set.
  void Say(const std::string& line) const {
    if (options.progress) options.progress(line);
  }
  // The robot's model name, else "robot N" (N from 1).
  std::string Name(int robot) const {
    return knowledge.nominal[robot].name.empty() ? "robot " + std::to_string(robot + 1)
                                                 : knowledge.nominal[robot].name;
  }
  // Moves `robot` back to its start pose; throws InputError when it does not settle.
  void GoHome(int robot) const {
    const MoveResult m = MoveAvoidingSweep(cell, robot, home[robot]);
    if (m.status != MoveStatus::kSettled) {
      throw InputError(Name(robot), std::string("cannot return to the start pose: ") +
                                        ToString(m.status) + ": " + m.reason);
    }
  }
};

// Sets the flag when destroyed, so background planners stop early.
struct CancelOnExit {
  std::shared_ptr<std::atomic<bool>> flag;
  ~CancelOnExit() { flag->store(true); }
};

// Throws as ValidateOpticalAxisOptions for bad options, PreconditionError for bad board
// geometries (bounded where the scenario is read), InputError for bad nominal models.
void ValidateProcedureInputs(const CellKnowledge& knowledge, const OpticalAxisOptions& options) {
  ValidateOpticalAxisOptions(options);
  ValidateBoardGeometry(knowledge.board, "CellKnowledge.board");
  if (knowledge.intrinsics_target) {
    ValidateBoardGeometry(*knowledge.intrinsics_target, "CellKnowledge.intrinsics_target");
  }
  for (int k = 0; k < 2; ++k) ValidateModel(knowledge.nominal[k], "CellKnowledge.nominal[" + std::to_string(k) + "]");
}

// Starts every robot's pose planning (section IV) in the background, one job per robot.
void StartBackgroundPlanning(const ProcedureContext& ctx,
                             const std::shared_ptr<std::atomic<bool>>& cancel,
                             std::map<int, std::future<PlanOutcome>>* plan_jobs) {
  const CellKnowledge& knowledge = ctx.knowledge;
  const OpticalAxisOptions& options = ctx.options;
  for (const int r : options.robots) {
    const int a = 1 - r;
    PlanInputs inputs{knowledge.nominal[a], BoardRobotModel(knowledge.nominal[r], knowledge.X_FT),
                      a == 0 ? knowledge.X_B1B2 : Transform(knowledge.X_B1B2.inverse()),
                      knowledge.X_FC, options.planner};
    if (options.plan_from_start_pose) {
      inputs.options.active_ik_seed = ctx.home[a];
      inputs.options.passive_ik_seed = ctx.home[r];
    }
    ctx.Say(ctx.Name(r) + ": planning " + std::to_string(options.planner.num_axes) + " axes x " +
            std::to_string(options.planner.positions_per_axis) + " positions (PSO, " +
            std::to_string(options.planner.runs) + " runs x " +
            std::to_string(options.planner.iterations) + " iterations), in the background");
    (*plan_jobs)[r] = std::async(std::launch::async, PlanWithStore, std::move(inputs),
                                 options.plan_store, cancel);
  }
}

// Mounts `target` on the board's bracket; throws InputError when the exchange does not settle.
void MountIntrinsicsBracketTarget(Cell& cell, BracketTarget target) {
  const MoveResult m = cell.MountTarget(target);
  if (m.status != MoveStatus::kSettled) {
    throw InputError("intrinsics", std::string("cannot mount the ") + ToString(target) +
                                       ": " + ToString(m.status) + ": " + m.reason);
  }
}

// The board robot's joint angles of the intrinsics views, designed in the camera frame
// (spread over the image, tilted) from the rough knowledge: the camera in its base.
std::vector<JointVector> IntrinsicsViewPoses(const ProcedureContext& ctx, int board_robot,
                                             const BoardGeometry& plate) {
  const CellKnowledge& knowledge = ctx.knowledge;
  const int camera_robot = 1 - board_robot;
  const Transform X_BbBa = board_robot == 1 ? Transform(knowledge.X_B1B2.inverse())
                                            : knowledge.X_B1B2;
  const Transform X_BbC =
      X_BbBa * ForwardKinematics(knowledge.nominal[camera_robot], ctx.home[camera_robot]).flange() *
      knowledge.X_FC;
  return PlannedIntrinsicsViews(
      BoardRobotModel(knowledge.nominal[board_robot], knowledge.X_FT), ctx.home[board_robot], X_BbC,
      ctx.options.intrinsics_views, ctx.options.seed, IntrinsicsViewSpecFor(plate));
}

// Section VI.A: Zhang's method from board (or intrinsics target) views around the start pose;
// fills out->intrinsics and intrinsics_s, throws InputError when it fails.
void CalibrateCameraIntrinsics(const ProcedureContext& ctx, OpticalAxisResult* out) {
  const CellKnowledge& knowledge = ctx.knowledge;
  const OpticalAxisOptions& options = ctx.options;
  const auto t0 = Clock::now();
  const int board_robot = 1 - ctx.cell.CameraRobot();
  const bool dedicated = knowledge.intrinsics_target.has_value();
  const BoardGeometry& plate = dedicated ? *knowledge.intrinsics_target : knowledge.board;
  if (dedicated) {
    ctx.Say("intrinsics: mounting the intrinsics target (" + std::to_string(plate.squares_x) +
            " x " + std::to_string(plate.squares_y) + " squares of " +
            Fixed(plate.square_m * 1e3, 1) + " mm)");
    MountIntrinsicsBracketTarget(ctx.cell, BracketTarget::kIntrinsicsTarget);
  }
  ctx.Say("intrinsics: " + std::to_string(options.intrinsics_views) + " " +
          (dedicated ? "target" : "board") + " views (Zhang)");
  const std::vector<JointVector> views = IntrinsicsViewPoses(ctx, board_robot, plate);
  out->intrinsics = CalibrateIntrinsics(ctx.cell, board_robot, views, plate, options.intrinsics);
  ctx.GoHome(board_robot);
  if (dedicated) {
    MountIntrinsicsBracketTarget(ctx.cell, BracketTarget::kFeatureBoard);
    ctx.Say("intrinsics: feature board mounted again");
  }
  out->intrinsics_s = SecondsSince(t0);
  if (out->intrinsics.status != IntrinsicsStatus::kSuccess) {
    throw InputError("intrinsics", std::string(ToString(out->intrinsics.status)) + ": " +
                                       out->intrinsics.reason +
                                       " (does the camera see the board at the start pose?)");
  }
  const PinholeIntrinsics& k = out->intrinsics.intrinsics;
  ctx.Say("intrinsics: fx " + Fixed(k.fx, 2) + ", fy " + Fixed(k.fy, 2) + ", cx " +
          Fixed(k.cx, 2) + ", cy " + Fixed(k.cy, 2) + " px, RMS " +
          Fixed(out->intrinsics.rms_px, 3) + " px from " +
          std::to_string(out->intrinsics.views_used) + " views");
}

// Section II: puts the camera on the other robot than r (both robots home first), unless it
// is there already; throws InputError when the exchange fails.
void PutCameraOnOtherRobot(const ProcedureContext& ctx, int r) {
  const int a = 1 - r;
  if (ctx.cell.CameraRobot() != a) {
    ctx.GoHome(0);
    ctx.GoHome(1);
    ctx.Say("exchanging camera and board: " + ctx.Name(r) + " becomes the passive robot");
    const MoveResult ex = ctx.cell.ExchangeTools();
    if (ex.status != MoveStatus::kSettled || ctx.cell.CameraRobot() != a) {
      throw InputError(ctx.Name(r), std::string("cannot exchange the tools: ") +
                                        ToString(ex.status) + ": " + ex.reason);
    }
  }
}

// Section IV: waits for rc's robot's background plan and reports it; throws InputError (or
// rethrows the planner's exception) when there is no feasible plan.
void CollectPlan(const ProcedureContext& ctx, std::map<int, std::future<PlanOutcome>>* plan_jobs,
                 RobotCalibration* rc) {
  const int r = rc->robot;
  const auto t0 = Clock::now();
  PlanOutcome planned_outcome = plan_jobs->at(r).get();  // rethrows the planner's exception
  rc->plan = std::move(planned_outcome.plan);
  rc->plan_from_store = planned_outcome.from_store;
  rc->plan_compute_s = planned_outcome.seconds;
  rc->planning_s = SecondsSince(t0);
  if (rc->plan.status != PosePlannerStatus::kSuccess) {
    throw InputError(ctx.Name(r) + " planning", rc->plan.reason);
  }
  std::ostringstream os;
  os.precision(4);
  os << ctx.Name(r) << ": best fitness 1/O1 = " << rc->plan.best_fitness << " (run "
     << rc->plan.best_run + 1 << "), "
     << (rc->plan_from_store ? std::string("from the plan store (same planner inputs)")
                             : Fixed(rc->plan_compute_s, 1) + " s in the background")
     << ", waited " << Fixed(rc->planning_s, 1) << " s";
  ctx.Say(os.str());
}

// What the servo of one passive robot shares over all its axes and positions.
struct RobotServo {
  int passive = 0, active = 1;               // robot indices (board, camera)
  int num_axes = 0;                          // axes of the plan
  const IntrinsicsResult* intrinsics = nullptr;  // the intrinsics step's result
  ServoSetup setup;                          // q_active set per axis
  ServoStepModel step_model;                 // learnt over this robot's poses
  AxisStartPredictor start_predictor;        // the plan's miss, learnt over this robot's poses
};

// What one position of an optical axis hands to the next.
struct AxisServoState {
  int axis = 0;                        // plan axis index
  int positions = 0;                   // planned positions on it
  Matrix3 R_BpC = Matrix3::Identity();  // camera in the passive base (eq. 43)
  Vector3 axis_Bp = Vector3::Zero();   // the optical axis's direction in the passive base
  Vector3 correction = Vector3::Zero();  // aligned less planned P at the last aligned position
  bool have_correction = false;
  cv::Rect next_region;                // where the board should appear at the next position
};

// Measurement step 1 of VI.C: the passive robot to the axis's first position, then the active
// robot to its pose, with one retry from the start poses.
MoveResult MoveRobotsOntoAxis(const ProcedureContext& ctx, int r, int a, const PlannedAxis& axis) {
  Cell& cell = ctx.cell;
  MoveResult m = MoveAvoidingSweep(cell, r, axis.q_passive[0]);
  if (m.status == MoveStatus::kSettled) m = MoveAvoidingSweep(cell, a, axis.q_active);
  if (m.status != MoveStatus::kSettled) {
    // One retry from the start poses (a path between two planned poses may sweep through
    // the other robot).
    if (MoveAvoidingSweep(cell, r, ctx.home[r]).status == MoveStatus::kSettled &&
        MoveAvoidingSweep(cell, a, axis.q_active).status == MoveStatus::kSettled) {
      m = MoveResult{};
    }
  }
  return m;
}

// The passive joint angles the servo starts from at `planned`: shifted by the correction found
// at this axis's previous position, else (its first position, or none aligned yet) by the
// miss predicted from the other axes' positions, where IK reaches the shifted pose.
JointVector ServoStartJoints(const OpticalAxisOptions& options, const RobotServo& servo,
                             const AxisServoState& state, const KinematicModel& nominal,
                             const JointVector& planned, const Transform& planned_pose,
                             const Vector3& planned_P) {
  JointVector start = planned;
  Vector3 start_shift = Vector3::Zero();
  if (options.carry_correction && state.have_correction) {
    start_shift = state.correction;
  } else if (options.predict_axis_start && servo.start_predictor.positions() > 0) {
    start_shift = servo.start_predictor.Correction(planned_P);
  }
  if (start_shift.squaredNorm() > 0) {
    Transform target = planned_pose;
    target.translation() += start_shift;
    IkOptions ik_options;
    ik_options.seed = options.servo.ik_seed;
    const IkResult ik = SolveIk(nominal, target, planned, ik_options);
    if (ik.status == IkStatus::kSuccess && WithinLimits(nominal, ik.q)) start = ik.q;
  }
  return start;
}

// OpticalAxisOptions::board_pose_test_p: true (the pose listed as failed, its image kept for
// the report, the reason said) when the board pose's corners do not fit the corner noise.
bool RefuseInconsistentBoardPose(const ProcedureContext& ctx, const RobotServo& servo, int k,
                                 int i, const ServoResult& sr, const BoardPose& pose,
                                 const std::string& where, RobotCalibration* rc) {
  const OpticalAxisOptions& options = ctx.options;
  const BoardPose* fp = &pose;
  if (options.board_pose_test_p > 0) {
    // The corner noise: the intrinsics' RMS reprojection error over every corner.
    const double sigma = servo.intrinsics->rms_px;
    const BoardPoseTest test = TestBoardPose(*fp, sigma);
    if (test.p_value < options.board_pose_test_p) {
      const std::string why =
          "the board pose reprojects its corners with RMS " +
          Fixed(fp->reprojection_rms_px, 3) + " px against the corner noise " +
          Fixed(sigma, 3) + " px (chi-square " + Fixed(test.statistic, 1) + " on " +
          Fixed(test.dof, 0) + " dof, p " + Sci(test.p_value) + " < " +
          Sci(options.board_pose_test_p) + "): a misplaced corner";
      rc->failed.push_back({k, i, "board_pose_inconsistent", why, sr.frames});
      if (static_cast<int>(rc->refused_images.size()) < options.kept_images) {
        RefusedPoseImage im;
        im.axis = k;
        im.index = i;
        im.image = sr.image_after;
        im.origin = sr.image_after_origin;
        im.detected.assign(sr.detection_after.corners.begin(),
                           sr.detection_after.corners.end());
        im.reprojected = fp->reprojected;
        im.rms_px = fp->reprojection_rms_px;
        rc->refused_images.push_back(im);
      }
      ctx.Say(where + ": skipped: " + why);
      return true;
    }
  }
  return false;
}

// Measurement step 3 of VI.C: the aligned pose and its sample (offset and depth from the board
// pose, the cell's clock and temperature) recorded in rc.
void RecordAlignedPose(const ProcedureContext& ctx, const RobotServo& servo,
                       const AxisServoState& state, int i, const ServoResult& sr,
                       const BoardPose& pose, RobotCalibration* rc) {
  const BoardPose* fp = &pose;
  AlignedPose ap;
  ap.axis = state.axis;
  ap.index = i;
  ap.q_passive = sr.q_passive;
  ap.q_active = servo.setup.q_active;
  ap.pixel_error = sr.pixel_error;
  const Vector3* p_C = &fp->p_C;
  ap.p_C = *p_C;
  ap.offset = state.R_BpC * Vector3(p_C->x(), p_C->y(), 0.0);
  ap.pose_rms_px = fp->reprojection_rms_px;
  ap.frames = sr.frames;
  ap.moves = sr.moves;
  ap.region_frames = sr.region_frames;
  ap.full_frame_fallbacks = sr.full_frame_fallbacks;
  ap.first_pixel_error = sr.first_pixel_error;
  ap.time_s = ctx.cell.ClockSeconds();  // NaN where the cell keeps no clock
  // The arm's temperature sensor where it has one (a thermal growth is then a function
  // of the reading, no extrapolation in time): relative to the first aligned pose's.
  ap.temperature_delta_K =
      ReadTemperatureDeltaK(ctx.cell, servo.passive, &rc->temperature_reference_C);
  rc->aligned.push_back(ap);
  AxisSample smp;
  smp.axis = state.axis;
  smp.q = sr.q_passive;
  smp.offset = ap.offset;
  smp.depth = p_C->z();
  smp.sigma_offset = std::sqrt(0.5 * (fp->covariance(0, 0) + fp->covariance(1, 1)));
  smp.sigma_depth = std::sqrt(fp->covariance(2, 2));
  smp.approach = sr.approach;
  smp.time_s = ap.time_s;
  smp.temperature_delta_K = ap.temperature_delta_K;
  rc->samples.push_back(smp);
}

// What the next position starts from: the correction found here, this position added to the
// start predictor, and (regions) where the board should appear next.
void CarryToNextPosition(const OpticalAxisOptions& options, const Vector3& planned_P,
                         const ServoResult& sr, const KinematicModel& nominal,
                         RobotServo* servo, AxisServoState* state) {
  const Vector3 aligned_P = EndPose(nominal, sr.q_passive).translation();
  state->correction = aligned_P - planned_P;
  state->have_correction = true;
  servo->start_predictor.Add(planned_P, aligned_P, state->axis_Bp);
  if (options.servo.use_regions && options.carry_correction) {
    // The next position starts on the axis again (carried correction), 20 mm along it:
    // the board stays about where it is, a few percent larger or smaller.
    state->next_region = PredictBoardRegion(sr.detection_after, cv::Point2d(0, 0),
                                            options.servo.region_margin_squares + 1.0,
                                            options.servo.region_slack_px,
                                            cv::Size(1 << 20, 1 << 20));
  }
}

// `part` (a region at `origin`, or the whole frame) in place on a black frame of size `frame`.
cv::Mat InFrame(const cv::Mat& part, const cv::Point& origin, const cv::Size& frame) {
  if (origin == cv::Point(0, 0) && part.size() == frame) return part;
  cv::Mat full(frame, part.type(), cv::Scalar::all(0));
  const cv::Rect r = cv::Rect(origin, part.size()) & cv::Rect(cv::Point(0, 0), frame);
  part(cv::Rect(cv::Point(0, 0), r.size())).copyTo(full(r));
  return full;
}

// Fig. 12: the servo's first and last image of an axis's first position, kept for the report
// while fewer than options.kept_images are.
void KeepServoImages(const ProcedureContext& ctx, const RobotServo& servo, int k, int i,
                     const ServoResult& sr, RobotCalibration* rc) {
  if (static_cast<int>(rc->images.size()) < ctx.options.kept_images && i == 0) {
    ServoImages im;
    im.axis = k;
    im.index = i;
    // Regions shown in place on a black frame (what the camera did not read out).
    const cv::Size frame = sr.image_before_origin == cv::Point(0, 0)
                               ? sr.image_before.size()
                               : sr.image_after.size();
    im.before = InFrame(sr.image_before, sr.image_before_origin, frame);
    im.after = InFrame(sr.image_after, sr.image_after_origin, frame);
    FeatureDetection d0 = DetectFeaturePoint(sr.image_before, ctx.knowledge.board);
    ToFrameCoordinates(sr.image_before_origin, &d0);
    if (d0.status == DetectionStatus::kFound) {
      im.error_before = cv::Point2d(d0.feature_px.x - servo.setup.intrinsics.cx,
                                    d0.feature_px.y - servo.setup.intrinsics.cy);
    }
    im.error_after = sr.pixel_error;
    rc->images.push_back(im);
  }
}

// Measurement steps 2-3 of VI.C (section V.A, eq. 42-43): position i of an axis servoed onto
// it and, when aligned with a consistent board pose, recorded; otherwise listed as failed.
void ServoPosition(const ProcedureContext& ctx, const PlannedAxis& axis, int i,
                   RobotServo* servo, AxisServoState* state, RobotCalibration* rc) {
  const OpticalAxisOptions& options = ctx.options;
  const int k = state->axis;
  const JointVector& planned = axis.q_passive[i];
  const Transform planned_pose = EndPose(rc->nominal, planned);
  const Vector3 planned_P = planned_pose.translation();
  const JointVector start =
      ServoStartJoints(options, *servo, *state, rc->nominal, planned, planned_pose, planned_P);
  const ServoResult sr = AlignFeatureToOpticalAxis(
      ctx.cell, servo->setup, start, options.servo, state->next_region,
      options.learn_servo_steps ? &servo->step_model : nullptr);
  state->next_region = cv::Rect();
  std::string where = ctx.Name(servo->passive) + " axis " + std::to_string(k + 1) + "/" +
                      std::to_string(servo->num_axes) + " position " + std::to_string(i + 1) +
                      "/" + std::to_string(state->positions);
  if (sr.status != ServoStatus::kAligned) {
    rc->failed.push_back({k, i, ToString(sr.status), sr.reason, sr.frames});
    ctx.Say(where + ": skipped (" + ToString(sr.status) + "): " + sr.reason);
    return;
  }
  const std::optional<BoardPose> fp =
      EstimateBoardPose(sr.detection_after, ctx.knowledge.board, *servo->intrinsics);
  if (!fp) {
    rc->failed.push_back({k, i, "board_pose_failed",
                          "aligned, but solvePnP found no board pose in the last image",
                          sr.frames});
    ctx.Say(where + ": skipped: no board pose");
    return;
  }
  if (RefuseInconsistentBoardPose(ctx, *servo, k, i, sr, *fp, where, rc)) return;
  RecordAlignedPose(ctx, *servo, *state, i, sr, *fp, rc);
  CarryToNextPosition(options, planned_P, sr, rc->nominal, servo, state);
  KeepServoImages(ctx, *servo, k, i, sr, rc);
  const Vector3* p_C = &fp->p_C;
  ctx.Say(where + ": aligned in " + std::to_string(sr.frames) + " frames, (" +
          Fixed(sr.pixel_error.x, 3) + ", " + Fixed(sr.pixel_error.y, 3) + ") px, depth " +
          Fixed(1000.0 * p_C->z(), 1) + " mm");
}

// Measurement steps 1-4 of VI.C for plan axis k: the active robot to its pose, then each
// position servoed; every position is listed as failed when the robots cannot reach the axis.
void ServoAxis(const ProcedureContext& ctx, int k, RobotServo* servo, RobotCalibration* rc) {
  const int r = servo->passive, a = servo->active;
  const PlannedAxis& axis = rc->plan.axes[k];
  const int p = static_cast<int>(axis.q_passive.size());
  auto fail_axis = [&](const std::string& reason) {
    for (int i = 0; i < p; ++i) rc->failed.push_back({k, i, "active_move_failed", reason, 0});
    ctx.Say(ctx.Name(r) + ": axis " + std::to_string(k + 1) + " skipped: " + reason);
  };
  // Step 1: the active robot to its pose (after the passive robot moved to its first
  // position: the planned pair is collision-free by construction of the axis geometry).
  const MoveResult m = MoveRobotsOntoAxis(ctx, r, a, axis);
  if (m.status != MoveStatus::kSettled) {
    fail_axis(std::string(ToString(m.status)) + ": " + m.reason);
    return;
  }
  ServoSetup& setup = servo->setup;
  setup.q_active = ctx.cell.ReadEncoders(a);
  AxisServoState state;
  state.axis = k;
  state.positions = p;
  state.R_BpC = setup.R_BaBp.transpose() *
                ForwardKinematics(ctx.knowledge.nominal[a], setup.q_active).flange().linear() *
                setup.R_FC;
  // Steps 2-4: each position servoed onto the axis and its joint angles saved.
  state.axis_Bp = state.R_BpC.col(2);
  for (int i = 0; i < p; ++i) ServoPosition(ctx, axis, i, servo, &state, rc);
}

// Measurement steps 1-5 of section VI.C: every axis of rc's plan, the passive robot servoed
// onto it at each planned position (section V.A, eq. 42-43).
void ServoAllAxes(const ProcedureContext& ctx, const IntrinsicsResult& intrinsics,
                  const Transform& X_BaBp, RobotCalibration* rc) {
  const int r = rc->robot, a = rc->camera_robot;
  const auto t0 = Clock::now();
  RobotServo servo;
  servo.passive = r;
  servo.active = a;
  servo.intrinsics = &intrinsics;
  ServoSetup& setup = servo.setup;
  setup.active_model = ctx.knowledge.nominal[a];
  setup.passive_model = rc->nominal;
  setup.passive_robot = r;
  setup.R_BaBp = X_BaBp.linear();
  setup.R_FC = ctx.knowledge.X_FC.linear();
  setup.intrinsics = intrinsics.intrinsics;
  setup.board = ctx.knowledge.board;
  servo.num_axes = static_cast<int>(rc->plan.axes.size());
  for (int k = 0; k < servo.num_axes; ++k) ServoAxis(ctx, k, &servo, rc);
  rc->servoing_s = SecondsSince(t0);
}

// Section VI.C: splits rc's plan axes by whole axes into calibration and validation sets
// (ranked at the nominal model) and reports the choice.
void SplitRobotAxes(const ProcedureContext& ctx, std::vector<int>* cal_axes,
                    std::vector<int>* val_axes, RobotCalibration* rc) {
  const int num_axes = static_cast<int>(rc->plan.axes.size());
  const auto t_split = Clock::now();
  // The subsets are ranked at the nominal model. (From 551d510 to 2026-12-04 they were ranked
  // at the fit of every usable axis, rank first: that mended one validation miss at twice
  // Table 3's errors, 0.051 -> 0.011 mm, but on the ABB it picked subsets whose higher rank
  // came from weakly seen directions, and their six-axis models missed the held-out axes by
  // 0.1-0.2 mm in most calibrations; README.md of e5af83d, "Reverted".)
  const KinematicModel& split_at = rc->nominal;
  rc->split_at = "nominal model";
  SplitAxes(split_at, rc->samples, num_axes, ctx.options, cal_axes, val_axes,
            &rc->split_candidates);
  rc->identification_s += SecondsSince(t_split);
  if (!rc->split_candidates.empty()) {
    std::string axes;
    for (int k : *cal_axes) axes += (axes.empty() ? "" : ", ") + std::to_string(k + 1);
    ctx.Say(ctx.Name(rc->robot) + ": calibration axes " + axes + " of " +
            std::to_string(num_axes) + " (best conditioned of " +
            std::to_string(rc->split_candidates.size()) + " subsets)");
  }
}

// Section V.B: identifies rc's robot on the split and reports the misaligned errors (eq. 46).
void IdentifyAndReport(const ProcedureContext& ctx, const std::vector<int>& cal_axes,
                       const std::vector<int>& val_axes, RobotCalibration* rc) {
  const int r = rc->robot;
  ctx.Say(ctx.Name(r) + ": identifying from " + std::to_string(rc->samples.size()) +
          " aligned poses (" + std::to_string(rc->failed.size()) + " skipped)");
  IdentifyRobot(cal_axes, val_axes, ctx.options, rc);
  ctx.Say(ctx.Name(r) + ": mean misaligned error (eq. 46) calibration " +
          Fixed(1000 * rc->calibration_error.before, 4) + " -> " +
          Fixed(1000 * rc->calibration_error.after, 4) + " mm, validation " +
          Fixed(1000 * rc->validation_error.before, 4) + " -> " +
          Fixed(1000 * rc->validation_error.after, 4) + " mm (" + rc->method + ")");
}

// Steps 2-5 for passive robot r: roles, plan, servo, split and identification.
RobotCalibration CalibrateRobot(const ProcedureContext& ctx, int r,
                                const IntrinsicsResult& intrinsics,
                                std::map<int, std::future<PlanOutcome>>* plan_jobs) {
  const CellKnowledge& knowledge = ctx.knowledge;
  const int a = 1 - r;
  // 5. Roles: the camera must be on the other robot (section II: exchange the roles).
  PutCameraOnOtherRobot(ctx, r);
  RobotCalibration rc;
  rc.robot = r;
  rc.camera_robot = a;
  rc.nominal = BoardRobotModel(knowledge.nominal[r], knowledge.X_FT);
  const Transform X_BaBp = a == 0 ? knowledge.X_B1B2 : Transform(knowledge.X_B1B2.inverse());
  // 2a. Pose planning (section IV): started at the beginning, collected here.
  CollectPlan(ctx, plan_jobs, &rc);
  // 2b. Measurement steps 1-5 of section VI.C.
  ServoAllAxes(ctx, intrinsics, X_BaBp, &rc);
  // 3. Split by whole axes.
  std::vector<int> cal_axes, val_axes;
  SplitRobotAxes(ctx, &cal_axes, &val_axes, &rc);
  // 4. Identify (section V.B).
  IdentifyAndReport(ctx, cal_axes, val_axes, &rc);
  return rc;
}

}  // namespace

OpticalAxisResult RunOpticalAxisCalibration(Cell& cell, const CellKnowledge& knowledge,
                                            const OpticalAxisOptions& options) {
  // Options and knowledge checked before anything moves.
  ValidateProcedureInputs(knowledge, options);
  OpticalAxisResult out;
  // Where the cell starts: the camera sees the board (the scenario's set-up pose).
  const ProcedureContext ctx{cell, knowledge, options,
                             {cell.ReadEncoders(0), cell.ReadEncoders(1)}};

  // Pose planning (section IV) depends on the knowledge alone: every robot's plan starts now in
  // the background, overlapping the intrinsics and the servoing of the robots before it. The
  // plans do not depend on when or in which thread they run.
  auto cancel = std::make_shared<std::atomic<bool>>(false);
  std::map<int, std::future<PlanOutcome>> plan_jobs;
  // Declared after plan_jobs, so destroyed first: an exception below stops the planners early
  // instead of waiting for them.
  CancelOnExit cancel_on_exit{cancel};
  StartBackgroundPlanning(ctx, cancel, &plan_jobs);

  // 1. Intrinsics (section VI.A), board views around the start pose. With an intrinsics
  // target the operator swaps it onto the board's bracket first and back afterwards: Zhang's
  // method then sees many corners over a large part of the image in every view, where the
  // feature board gives it 3 x 3 corners over a few per cent of the image, which leaves the
  // focal length, and with it the scale of every measured depth, 1e-4..1e-3 off (README.md of
  // e5af83d).
  CalibrateCameraIntrinsics(ctx, &out);

  // 2-5. Each robot to calibrate in turn: plan, servo, split, identify.
  for (const int r : options.robots) {
    out.robots.push_back(CalibrateRobot(ctx, r, out.intrinsics, &plan_jobs));
  }
  return out;
}

}  // namespace twin
