#include "calib/procedures/tracker_calibration.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "calib/common/errors.h"
#include "calib/identification/dormant_restart.h"
#include "calib/model/parameter_layout.h"
#include "calib/model/robot_model.h"

namespace twin {
namespace {

struct Solved {
  IdentificationResult result;
  Transform X_TB = Transform::Identity();
};

Solved Solve(const RobotModel& start, const std::vector<TrackerPoint>& points,
             const TrackerSetOptions& set_options, const IdentificationOptions& options) {
  TrackerSet set(points, set_options);
  Solved s;
  s.result = Identify(start, {&set}, options);
  if (s.result.status == IdentificationStatus::kFailed) {
    throw InputError(set_options.source, "the identification failed: " + s.result.reason);
  }
  s.X_TB = set.X_TB();
  return s;
}

// A term whose dormant parameters sleep at the start (a declared warm-up: its time constant
// has no gradient while its growth is zero) is fitted once on `points`, and the calibration's
// fits start from that solution's values of it where KeepRestart says so (the one dormant-term
// restart, calib/identification/dormant_restart.h, as model discovery's).
RobotModel WokenStart(const RobotModel& start, const std::vector<TrackerPoint>& points,
                      const TrackerSetOptions& set_options, const IdentificationOptions& options) {
  if (!HasDormantTermsAtZero(start)) return start;
  const auto fit = [&](const RobotModel& model, bool) {
    return Solve(model, points, set_options, options);
  };
  return FitWithDormantRestart<Solved>(start, fit, WithDormantTermsWoken).model;
}

// Everything held but the reflector offset: the "before" of held-out scoring.
IdentificationOptions BaselineOptions(const RobotModel& model, IdentificationOptions options) {
  const std::vector<std::string> keep = ReflectorParameterNames(model);
  for (const std::string& name : ParameterLayout(model).names()) {
    if (std::find(keep.begin(), keep.end(), name) == keep.end()) options.fixed.push_back(name);
  }
  return options;
}

// Enough coordinates for the unknowns: 3 per point against the geometry and the tracker pose.
void RequireEnoughPoints(const RobotModel& model, int points, const std::string& what,
                         const std::string& source) {
  const int unknowns = model.chain.num_parameters() + 6;
  if (3 * points <= unknowns) {
    throw InputError(source, what + ": " + std::to_string(points) + " points give " +
                                 std::to_string(3 * points) + " coordinates, not more than the " +
                                 std::to_string(model.chain.num_parameters()) +
                                 " geometric parameters + 6 of the tracker pose (at least " +
                                 std::to_string(unknowns / 3 + 1) + " points needed)");
  }
}

std::vector<TrackerPoint> Pick(const std::vector<TrackerPoint>& points,
                               const std::vector<int>& index) {
  std::vector<TrackerPoint> out;
  out.reserve(index.size());
  for (int i : index) out.push_back(points[i]);
  return out;
}

std::string Mm(double m) {
  std::ostringstream os;
  os.precision(4);
  os << 1e3 * m << " mm";
  return os.str();
}

// Throws PreconditionError for a holdout fraction outside (0, 0.5] or bad engine options:
// the user's --holdout and tracker_calibration.holdout are bounded where they are read
// (bench/runs), and no user sets the engine's.
void ValidateCalibrationOptions(const TrackerCalibrationOptions& options) {
  TWIN_REQUIRE(options.holdout_fraction > 0.0 && options.holdout_fraction <= 0.5,
               "holdout fraction: expected a fraction in (0, 0.5], got " +
                   std::to_string(options.holdout_fraction));
  ValidateIdentificationOptions(options.engine);
  TWIN_REQUIRE(options.session.halvings >= 1 && options.session.halvings <= 1000,
               "session halvings: expected 1 to 1000, got " +
                   std::to_string(options.session.halvings));
}

/// The points' pose groups (PoseGroups: repeats of one pose share an index) and their count.
struct PoseGrouping {
  std::vector<int> pose_of;  ///< per point, the index of its pose
  int poses = 0;             ///< number of different poses
};

// Groups the points by pose.
PoseGrouping GroupPoses(const std::vector<TrackerPoint>& points) {
  PoseGrouping g;
  g.pose_of = PoseGroups(points);
  const std::vector<int>& pose_of = g.pose_of;
  g.poses = points.empty() ? 0 : *std::max_element(pose_of.begin(), pose_of.end()) + 1;
  return g;
}

// Identifies the delivered model on every point and scores it and the baseline on them all;
// returns the baseline model (the nominal one, its reflector offset fitted).
RobotModel FitDeliveredModel(const RobotModel& nominal, const RobotModel& start,
                       const std::vector<TrackerPoint>& points,
                       const TrackerCalibrationOptions& options,
                       const IdentificationOptions& baseline, TrackerCalibrationResult* out) {
  const Solved all = Solve(start, points, options.set, options.engine);
  const Solved before = Solve(nominal, points, options.set, baseline);
  out->identified = all.result;
  out->X_TB = all.X_TB;
  out->all_after = ScorePoints(all.result.model, all.X_TB, points);
  out->all_before = ScorePoints(before.result.model, before.X_TB, points);
  return before.result.model;
}

// The second session (the validation file): the baseline and the delivered model scored over
// the same halvings, each with its tracker pose refitted on half the file.
void ScoreSecondSession(const RobotModel& baseline, const std::vector<TrackerPoint>& validation,
                        const TrackerCalibrationOptions& options, TrackerCalibrationResult* out) {
  const std::string source = options.set.source + " (validation file)";
  const std::vector<SessionHalving> halvings =
      SessionHalvings(validation, options.session, source);
  out->session_nominal = ScoreModelOnSession(baseline, validation, halvings, source);
  out->session_geometric =
      ScoreModelOnSession(out->identified.model, validation, halvings, source);
}

// The number of points each split holds out: the holdout fraction of them, at least 1.
int HeldOutCount(const TrackerCalibrationOptions& options,
                 const std::vector<TrackerPoint>& points) {
  const int n = static_cast<int>(points.size());
  return std::max(1, static_cast<int>(std::lround(options.holdout_fraction * n)));
}

/// What every held-out split shares: the nominal model, the options and the baseline's.
struct SplitContext {
  const RobotModel& nominal;
  const TrackerCalibrationOptions& options;
  const IdentificationOptions& baseline;  ///< of the "before" fits
  int held = 0;                           ///< points held out by a split of the given points
};

/// One held-out split's parts: the points identified on and the points scored.
struct SplitParts {
  std::string name;  ///< "random" or "region"
  std::string rule;  ///< how the held-out points were chosen, for the report
  const std::vector<TrackerPoint>& train;  ///< the points identified on
  const std::vector<TrackerPoint>& test;   ///< the held-out points
  /// The held-out points come from another session (the tracker stood elsewhere), so each
  /// model's tracker pose is refitted to them (rigid least squares, 6 of their 3 n
  /// coordinates) before they are scored; the geometry stays as trained.
  bool refit_pose = false;
};

// The tracker pose a model's held-out points are scored through: its own, or refitted to
// them when `refit_pose`.
Transform PoseForTest(const Solved& m, const std::vector<TrackerPoint>& test, bool refit_pose,
                      const std::string& source) {
  if (!refit_pose) return m.X_TB;
  std::vector<Vector3> predicted, measured;
  for (const TrackerPoint& p : test) {
    predicted.push_back(EndPose(m.result.model, p.context).translation());
    measured.push_back(p.p_T);
  }
  Transform X = m.X_TB;
  if (!FitRigid(predicted, measured, &X)) {
    throw InputError(source, "the held-out file's points are fewer than 3 or collinear: no "
                             "tracker pose can be fitted to them");
  }
  return X;
}

// Identifies on the training part, scores before and after on the held-out part and adds
// the split (and a warning when the calibration is worse there) to `out`.
void RunSplit(const SplitContext& ctx, const SplitParts& parts, TrackerCalibrationResult* out) {
  const RobotModel& nominal = ctx.nominal;
  const TrackerCalibrationOptions& options = ctx.options;
  const std::string& source = options.set.source;
  const std::string& name = parts.name;
  const std::vector<TrackerPoint>& train = parts.train;
  const std::vector<TrackerPoint>& test = parts.test;
  HeldOutSplit s;
  s.name = name;
  s.rule = parts.rule;
  s.training = static_cast<int>(train.size());
  RequireEnoughPoints(nominal, s.training, "the " + name + " split's training part", source);
  TrackerSetOptions so = options.set;
  so.source = source + " (" + name + " split, training part)";
  const Solved after = Solve(WokenStart(nominal, train, so, options.engine), train, so,
                             options.engine);
  const Solved before = Solve(nominal, train, so, ctx.baseline);
  s.after = ScorePoints(after.result.model, PoseForTest(after, test, parts.refit_pose, source),
                        test);
  s.before = ScorePoints(before.result.model,
                         PoseForTest(before, test, parts.refit_pose, source), test);
  s.training_after = ScorePoints(after.result.model, after.X_TB, train);
  s.worse = s.after.rms > s.before.rms;
  if (s.worse) {
    out->warnings.push_back("held-out " + name + " split: the calibrated model is WORSE than the "
                            "nominal one on the points it did not see (RMS " + Mm(s.after.rms) +
                            " after against " + Mm(s.before.rms) + " before)");
  }
  out->splits.push_back(s);
}

// The random split: whole poses, in a seeded shuffle, held out until `held` points are.
void RunRandomSplit(const SplitContext& ctx, const std::vector<TrackerPoint>& points,
                    const PoseGrouping& grouping, TrackerCalibrationResult* out) {
  const TrackerCalibrationOptions& options = ctx.options;
  const std::vector<int>& pose_of = grouping.pose_of;
  const int poses = grouping.poses;
  const int n = static_cast<int>(points.size());
  const int held = ctx.held;
  // Whole poses are held out: a repeat of a training pose is no held-out point. Without
  // repeats this is a shuffle of the points.
  std::vector<int> pose_order(poses);
  std::iota(pose_order.begin(), pose_order.end(), 0);
  std::mt19937_64 rng(options.seed);
  std::shuffle(pose_order.begin(), pose_order.end(), rng);
  std::vector<std::vector<int>> members(poses);
  for (int i = 0; i < n; ++i) members[pose_of[i]].push_back(i);
  std::vector<int> test, train;
  for (const int g : pose_order) {
    std::vector<int>& part = static_cast<int>(test.size()) < held ? test : train;
    part.insert(part.end(), members[g].begin(), members[g].end());
  }
  const std::vector<TrackerPoint> train_points = Pick(points, train);
  const std::vector<TrackerPoint> test_points = Pick(points, test);
  RunSplit(ctx,
           {"random",
            std::to_string(test.size()) + " of " + std::to_string(n) + " points held out at " +
                "random" + (poses < n ? " as whole poses (" + std::to_string(n - poses) +
                                            " rows repeat a pose)"
                                      : std::string()) +
                " (seed " + std::to_string(options.seed) + ")",
            train_points, test_points, false},
           out);
}

/// The points farthest along the measured cloud's principal axis, and how they were found.
struct AxisRegion {
  Vector3 mean = Vector3::Zero();  ///< the cloud's centre in the tracker frame [m]
  Vector3 axis = Vector3::Zero();  ///< its principal axis (unit, a fixed sign)
  std::vector<int> test, train;    ///< indices of the held-out and the training points
};

// Holds out the `held` points farthest along the cloud's principal axis.
AxisRegion FarEndAlongPrincipalAxis(const std::vector<TrackerPoint>& points, int held) {
  const int n = static_cast<int>(points.size());
  AxisRegion region;
  Vector3& mean = region.mean;
  for (const TrackerPoint& p : points) mean += p.p_T;
  mean /= n;
  Matrix3 C = Matrix3::Zero();
  for (const TrackerPoint& p : points) C += (p.p_T - mean) * (p.p_T - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Matrix3> eig(C);
  Vector3& axis = region.axis;
  axis = eig.eigenvectors().col(2);  // largest spread
  if (axis(std::abs(axis(0)) >= std::abs(axis(1)) ? (std::abs(axis(0)) >= std::abs(axis(2)) ? 0 : 2)
                                                   : (std::abs(axis(1)) >= std::abs(axis(2)) ? 1 : 2)) < 0) {
    axis = -axis;  // a fixed sign: the far end along the dominant positive direction
  }
  std::vector<int> index(n);
  std::iota(index.begin(), index.end(), 0);
  std::stable_sort(index.begin(), index.end(), [&](int a, int b) {
    return axis.dot(points[a].p_T) > axis.dot(points[b].p_T);
  });
  region.test.assign(index.begin(), index.begin() + held);
  region.train.assign(index.begin() + held, index.end());
  return region;
}

// The region split: the validation file when there is one, else the far end of the cloud.
void RunRegionSplit(const SplitContext& ctx, const std::vector<TrackerPoint>& points,
                    const std::vector<TrackerPoint>& validation, TrackerCalibrationResult* out) {
  const int n = static_cast<int>(points.size());
  const int held = ctx.held;
  if (!validation.empty()) {
    RunSplit(ctx,
             {"region",
              "trained on all " + std::to_string(n) + " points, held out: the " +
                  std::to_string(validation.size()) + " points of the validation file (its "
                  "tracker pose refitted to them, the geometry as trained)",
              points, validation, true},
             out);
  } else {
    const AxisRegion region = FarEndAlongPrincipalAxis(points, held);
    const Vector3& axis = region.axis;
    const std::vector<int>& test = region.test;
    std::ostringstream rule;
    rule.precision(3);
    rule << held << " of " << n << " points farthest along the measured cloud's principal axis ("
         << axis(0) << ", " << axis(1) << ", " << axis(2) << ") in the tracker frame, beyond "
         << 1e3 * (axis.dot(points[test.back()].p_T - region.mean)) << " mm from its centre";
    const std::vector<TrackerPoint> train_points = Pick(points, region.train);
    const std::vector<TrackerPoint> test_points = Pick(points, test);
    RunSplit(ctx, {"region", rule.str(), train_points, test_points, false}, out);
  }
}

}  // namespace

std::vector<std::string> ReflectorParameterNames(const RobotModel& model) {
  const ParameterLayout layout(model);
  const int tool = 5 * model.chain.num_joints();  // the tool link's block: theta, d, a, ...
  return {layout[tool].name, layout[tool + 1].name, layout[tool + 2].name};
}

PointErrors ScorePoints(const RobotModel& model, const Transform& X_TB,
                        const std::vector<TrackerPoint>& points) {
  PointErrors e;
  e.poses = static_cast<int>(points.size());
  double sum = 0, sum_sq = 0;
  for (const TrackerPoint& p : points) {
    const double d = (X_TB * EndPose(model, p.context).translation() - p.p_T).norm();
    sum += d;
    sum_sq += d * d;
    e.max = std::max(e.max, d);
  }
  if (e.poses > 0) {
    e.mean = sum / e.poses;
    e.rms = std::sqrt(sum_sq / e.poses);
  }
  return e;
}

TrackerCalibrationResult CalibrateFromTracker(const RobotModel& nominal,
                                              const std::vector<TrackerPoint>& points,
                                              const std::vector<TrackerPoint>& validation,
                                              const TrackerCalibrationOptions& options) {
  // The holdout fraction and the engine's options.
  ValidateCalibrationOptions(options);
  // Repeats of one pose grouped, and enough poses for the unknowns.
  const PoseGrouping grouping = GroupPoses(points);
  RequireEnoughPoints(nominal, grouping.poses, "all points", options.set.source);
  TrackerCalibrationResult out;
  const IdentificationOptions baseline = BaselineOptions(nominal, options.engine);
  // The start of the calibrated ("after") fits; the "before" ones hold the terms as given.
  // Each held-out split wakes its own from its training part: no start of a fit scored on
  // held-out points comes from a fit that saw them.
  const RobotModel start = WokenStart(nominal, points, options.set, options.engine);

  // The delivered model: every point.
  const RobotModel fitted_nominal =
      FitDeliveredModel(nominal, start, points, options, baseline, &out);

  const SplitContext split{nominal, options, baseline, HeldOutCount(options, points)};
  // (a) Random: a seeded shuffle.
  RunRandomSplit(split, points, grouping, &out);
  // (b) Region: a separate file, or the far end along the principal axis of the cloud.
  RunRegionSplit(split, points, validation, &out);
  // (c) The second session, when there is one: both models over the same halvings.
  if (!validation.empty()) ScoreSecondSession(fitted_nominal, validation, options, &out);
  return out;
}

}  // namespace twin
