#include "calib/planning/pose_planner.h"

#include <atomic>
#include <thread>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <sstream>
#include <tuple>
#include <utility>

#include "calib/common/cpus.h"
#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "calib/kinematics/spherical_wrist_ik.h"
#include "calib/identification/linearized_identification.h"
#include "calib/identification/nonlinear_identification.h"
#include "calib/identification/observability.h"
#include "calib/measurements/optical_axis_model.h"

namespace twin {
namespace {

constexpr int kAxisHead = 7;     // P_c (3), yaw, pitch, camera roll, D
constexpr int kPerPosition = 3;  // tilt a, tilt b, board roll
constexpr double kInf = std::numeric_limits<double>::infinity();

enum class Cause { kNone, kActiveIk, kPassiveIk, kC1, kC2, kC3, kC4, kC5 };

void Count(Cause c, RejectionCounts* r) {
  switch (c) {
    case Cause::kActiveIk: ++r->active_ik; break;
    case Cause::kPassiveIk: ++r->passive_ik; break;
    case Cause::kC1: ++r->c1_joint_limits; break;
    case Cause::kC2: ++r->c2_singularity; break;
    case Cause::kC3: ++r->c3_visibility; break;
    case Cause::kC4: ++r->c4_min_distance; break;
    case Cause::kC5: ++r->c5_max_distance; break;
    case Cause::kNone: break;
  }
}

// The active model with an identity tool link, so that its end frame is the flange L_N.
KinematicModel FlangeModel(KinematicModel m) {
  m.tool().dh = DhParameters{};
  m.X_LtE = Transform::Identity();
  return m;
}

// Rotation taking unit vector a onto unit vector b about their common normal.
Eigen::AngleAxisd AlignRotation(const Vector3& a, const Vector3& b) {
  const Vector3 c = a.cross(b);
  const double sin_angle = c.norm();
  if (sin_angle > 1e-12) return Eigen::AngleAxisd(std::atan2(sin_angle, a.dot(b)), c / sin_angle);
  if (a.dot(b) > 0.0) return Eigen::AngleAxisd(0.0, Vector3::UnitZ());
  const Vector3 other = std::abs(a.x()) < 0.9 ? Vector3::UnitX() : Vector3::UnitY();
  return Eigen::AngleAxisd(kPi, a.cross(other).normalized());
}

// Eq. 24: min_i D_theta_i [rad].
double JointLimitDistance(const KinematicModel& m, const JointVector& q) {
  double d = kInf;
  for (int i = 0; i < m.num_joints(); ++i) {
    d = std::min({d, q(i) - m.links[i].limits.lower, m.links[i].limits.upper - q(i)});
  }
  return d;
}

// C1 and C2 of one configuration.
Cause CheckConfiguration(const KinematicModel& m, const JointVector& q,
                         const PosePlannerOptions& o, const ChainTrig& trig) {
  if (JointLimitDistance(m, q) < o.min_joint_limit_distance) return Cause::kC1;
  if (SmallestJacobianSingularValue(m, q, &trig) < o.min_singular_value) return Cause::kC2;
  return Cause::kNone;
}

struct Planner {
  KinematicModel active;   // flange model
  KinematicModel passive;
  ChainTrig active_trig, passive_trig;  // of the two models (repeated FK)
  Transform X_BaBp;
  Transform X_BpBa;
  Transform X_CF;
  PosePlannerOptions o;
  Vector3 h, s, z;         // Bp: towards Bp (horizontal), z x h, up
  Eigen::VectorXd lo, hi;  // bounds of one sub-particle
  int dim = 0;             // of one sub-particle

  IkOptions ik;            // o.ik; without random restarts where a start pose seeds the IK
  // The closed forms of the two models where they have a spherical wrist and
  // o.closed_form_ik (else empty: the iterative solver).
  std::optional<SphericalWristIk> active_ik, passive_ik;

  // The joints of one robot for end pose X_BE, from `seed`, checked against C1 and C2 into
  // *q. From the mid-range, the closed form tries its answers inside the limits nearest the
  // seed (the mid-range, or the board position before on the axis) first and takes the
  // first that passes (the nearest where it passes), as the iterative solver's random
  // restarts reach other branches; the cause is the nearest answer's. With a start pose it
  // takes the nearest alone: the seed's branch, as the iterative solver without restarts.
  // The iterative solver gives one answer (turned by whole turns to the seed's angles with a
  // start pose).
  Cause Solve(const KinematicModel& m, const std::optional<SphericalWristIk>& closed,
              const ChainTrig& trig, const Transform& X_BE, const JointVector& seed,
              bool start_pose, Cause ik_failed, JointVector* q) const {
    if (closed && closed->Serves(seed, ik)) {
      const std::vector<JointVector> answers = closed->InsideLimits(X_BE, seed);
      Cause nearest = ik_failed;
      const size_t tried = start_pose ? std::min<size_t>(answers.size(), 1) : answers.size();
      for (size_t k = 0; k < tried; ++k) {
        const Cause c = CheckConfiguration(m, answers[k], o, trig);
        if (c == Cause::kNone) {
          *q = answers[k];
          return c;
        }
        if (k == 0) nearest = c;
      }
      if (!answers.empty()) return nearest;
    }
    const IkResult r = SolveIk(m, X_BE, seed, ik);
    if (r.status != IkStatus::kSuccess) return ik_failed;
    *q = start_pose ? NearestTurns(m, r.q, seed) : r.q;
    return CheckConfiguration(m, *q, o, trig);
  }

  // Decodes sub-particle x, solves IK for both robots and checks C1-C5 (eq. 25-33).
  Cause Evaluate(const double* x, PlannedAxis* out) const {
    const Vector3 p_c(x[0], x[1], x[2]);
    const double yaw = x[3], pitch = x[4], roll = x[5], D = x[6];
    const Vector3 mu = (std::cos(pitch) * std::cos(yaw) * h + std::cos(pitch) * std::sin(yaw) * s +
                        std::sin(pitch) * z).normalized();
    const Vector3 ref = std::abs(mu.dot(z)) < 0.9 ? z : h;
    const Vector3 x0 = ref.cross(mu).normalized();
    const Vector3 x_c = std::cos(roll) * x0 + std::sin(roll) * mu.cross(x0);
    Transform X_BpC = Transform::Identity();
    X_BpC.linear().col(0) = x_c;
    X_BpC.linear().col(1) = mu.cross(x_c);
    X_BpC.linear().col(2) = mu;
    X_BpC.translation() = p_c;

    JointVector q_a;
    if (Cause c = Solve(active, active_ik, active_trig, X_BaBp * X_BpC * X_CF,
                        o.active_ik_seed.size() ? o.active_ik_seed : MidRange(active),
                        o.active_ik_seed.size() > 0, Cause::kActiveIk, &q_a);
        c != Cause::kNone) {
      return c;
    }
    // Camera as the active robot actually reaches it (within IK tolerance).
    const Transform X_BpC_fk = X_BpBa * EndPose(active, q_a, &active_trig) * X_CF.inverse();

    out->camera_origin = X_BpC_fk.translation();
    out->direction = X_BpC_fk.linear().col(2);
    out->q_active = q_a;
    out->q_passive.assign(o.positions_per_axis, ZeroJoints(passive));
    out->distances.assign(o.positions_per_axis, 0.0);
    JointVector seed = o.passive_ik_seed.size() ? o.passive_ik_seed : MidRange(passive);
    for (int i = 0; i < o.positions_per_axis; ++i) {
      const double* t = x + kAxisHead + kPerPosition * i;
      const Vector3 tilt = t[0] * x_c + t[1] * mu.cross(x_c);
      const double tilt_angle = tilt.norm();
      Vector3 n = -mu;
      if (tilt_angle > 0.0) n = Eigen::AngleAxisd(tilt_angle, tilt / tilt_angle) * n;
      Transform X_BpE = Transform::Identity();
      X_BpE.linear() = (Eigen::AngleAxisd(t[2], n) *
                        AlignRotation(o.board_normal_in_E, n))
                           .toRotationMatrix();
      const double d_i = D + i * o.distance_step;
      X_BpE.translation() = p_c + d_i * mu;
      JointVector q_p;
      if (Cause c = Solve(passive, passive_ik, passive_trig, X_BpE, seed,
                          o.passive_ik_seed.size() > 0, Cause::kPassiveIk, &q_p);
          c != Cause::kNone) {
        return c;
      }
      const Transform X_BpE_fk = EndPose(passive, q_p, &passive_trig);
      const Vector3 n_fk = X_BpE_fk.linear() * o.board_normal_in_E;
      const double visibility = std::acos(std::clamp(n_fk.dot(-out->direction), -1.0, 1.0));
      if (visibility > o.max_visibility_angle) return Cause::kC3;
      const double dist = (X_BpE_fk.translation() - out->camera_origin).norm();
      if (dist < o.min_distance) return Cause::kC4;
      if (dist > o.max_distance) return Cause::kC5;
      out->q_passive[i] = q_p;
      out->distances[i] = d_i;
      seed = q_p;
    }
    return Cause::kNone;
  }

  double Fitness(const std::vector<PlannedAxis>& axes) const {
    std::vector<std::vector<JointVector>> q;
    std::vector<Vector3> mu;
    for (const PlannedAxis& a : axes) {
      q.push_back(a.q_passive);
      mu.push_back(a.direction);
    }
    return PoseSetFitness(passive, q, mu, o.rank_tolerance);
  }
};

struct Particle {
  Eigen::VectorXd x, v, best_x;
  std::vector<PlannedAxis> axes, best_axes;
  double f = kInf, best_f = kInf;
};

std::string CountsText(const RejectionCounts& r) {
  std::ostringstream s;
  s << "rejected: active_ik " << r.active_ik << ", passive_ik " << r.passive_ik << ", C1 "
    << r.c1_joint_limits << ", C2 " << r.c2_singularity << ", C3 " << r.c3_visibility << ", C4 "
    << r.c4_min_distance << ", C5 " << r.c5_max_distance;
  return s.str();
}

// A field no user can set badly (the scenario's planning keys are bounded where they are
// read, bench/io/calibration_config.cc): a bad value is our bug.
void Require(bool ok, const std::string& field, double value, const std::string& expected) {
  if (!ok) {
    std::ostringstream s;
    s << "PosePlannerOptions." << field << " = " << value << ", expected " << expected;
    FailPrecondition("valid PosePlannerOptions", s.str(), __FILE__, __LINE__);
  }
}

}  // namespace

int RejectionCounts::total() const {
  return active_ik + passive_ik + c1_joint_limits + c2_singularity + c3_visibility +
         c4_min_distance + c5_max_distance;
}

const char* ToString(PosePlannerStatus status) {
  switch (status) {
    case PosePlannerStatus::kSuccess: return "success";
    case PosePlannerStatus::kNoFeasiblePoses: return "no_feasible_poses";
  }
  return "unknown";
}

void ValidatePosePlannerOptions(const PosePlannerOptions& o) {
  Require(o.num_axes >= 1, "num_axes", o.num_axes, ">= 1");
  Require(o.threads >= 0, "threads", o.threads, ">= 0 (0: one per hardware thread)");
  Require(o.positions_per_axis >= 3, "positions_per_axis", o.positions_per_axis, ">= 3");
  Require(o.swarm_size >= 1, "swarm_size", o.swarm_size, ">= 1");
  Require(o.iterations >= 0, "iterations", o.iterations, ">= 0");
  Require(o.runs >= 1, "runs", o.runs, ">= 1");
  Require(o.prediction_configurations >= 1, "prediction_configurations",
          o.prediction_configurations, ">= 1");
  Require(std::isfinite(o.inertia) && o.inertia >= 0.0, "inertia", o.inertia, "finite >= 0");
  Require(std::isfinite(o.learning_personal) && o.learning_personal >= 0.0, "learning_personal",
          o.learning_personal, "finite >= 0");
  Require(std::isfinite(o.learning_global) && o.learning_global >= 0.0, "learning_global",
          o.learning_global, "finite >= 0");
  Require(o.max_velocity_fraction > 0.0 && o.max_velocity_fraction <= 1.0,
          "max_velocity_fraction", o.max_velocity_fraction, "in (0, 1]");
  Require(std::isfinite(o.min_joint_limit_distance) && o.min_joint_limit_distance >= 0.0,
          "min_joint_limit_distance", o.min_joint_limit_distance, "finite >= 0 rad");
  Require(std::isfinite(o.min_singular_value) && o.min_singular_value >= 0.0,
          "min_singular_value", o.min_singular_value, "finite >= 0");
  Require(o.max_visibility_angle > 0.0 && o.max_visibility_angle < kPi / 2,
          "max_visibility_angle", o.max_visibility_angle, "in (0, pi/2) rad");
  // The scenario's calibration.planning.min_distance_mm may be 0, which reaches this check.
  if (!(std::isfinite(o.min_distance) && o.min_distance > 0.0)) {
    std::ostringstream s;
    s << "= " << o.min_distance << ", expected finite > 0 m (calibration.planning.min_distance_mm)";
    throw InputError("PosePlannerOptions.min_distance", s.str());
  }
  Require(std::isfinite(o.max_distance) && o.max_distance > 0.0, "max_distance", o.max_distance,
          "finite > 0 m");
  Require(std::isfinite(o.planning_max_distance) && o.planning_max_distance > 0.0,
          "planning_max_distance", o.planning_max_distance, "finite > 0 m");
  Require(std::isfinite(o.distance_step) && o.distance_step > 0.0, "distance_step",
          o.distance_step, "finite > 0 m");
  Require(std::isfinite(o.camera_reach), "camera_reach", o.camera_reach, "finite");
  Require(std::isfinite(o.camera_height), "camera_height", o.camera_height, "finite");
  Require(std::isfinite(o.camera_region_half_extent) && o.camera_region_half_extent >= 0.0,
          "camera_region_half_extent", o.camera_region_half_extent, "finite >= 0 m");
  Require(o.axis_cone_half_angle >= 0.0 && o.axis_cone_half_angle < kPi / 2,
          "axis_cone_half_angle", o.axis_cone_half_angle, "in [0, pi/2) rad");
  Require(std::abs(o.board_normal_in_E.norm() - 1.0) < 1e-9, "board_normal_in_E",
          o.board_normal_in_E.norm(), "a unit vector (value is its norm)");
  Require(o.max_draws_per_axis >= 1, "max_draws_per_axis", o.max_draws_per_axis, ">= 1");
  Require(o.redraws_after_update >= 0, "redraws_after_update", o.redraws_after_update, ">= 0");
  Require(o.rank_tolerance > 0.0 && o.rank_tolerance < 1.0, "rank_tolerance", o.rank_tolerance,
          "in (0, 1)");
  ValidateIkOptions(o.ik);
}

// PredictedPositionError in `gauge` and, from the same pass, in the raw gauge (the planner
// reports both per run; one identifiability analysis and one set of Jacobians serve both).
static std::pair<double, double> PredictedErrorAndRaw(const KinematicModel& passive,
                                                      const std::vector<PlannedAxis>& axes,
                                                      double rank_tolerance, int configurations,
                                                      std::uint64_t seed, PredictionGauge gauge) {
  TWIN_REQUIRE(configurations >= 1,
               "configurations must be >= 1, got " + std::to_string(configurations));
  std::vector<AxisSample> samples;
  for (size_t k = 0; k < axes.size(); ++k) {
    for (size_t i = 0; i < axes[k].q_passive.size(); ++i) {
      AxisSample s;
      s.axis = static_cast<int>(k);
      s.q = axes[k].q_passive[i];
      if (i < axes[k].distances.size()) s.depth = axes[k].distances[i];
      samples.push_back(s);
    }
  }
  NonlinearIdentificationOptions options;
  options.rank_tolerance = rank_tolerance;
  const ObservabilityReport o = NonlinearIdentifiability(passive, samples, options);
  const int n = passive.num_parameters();
  if (o.rank < 1 || o.identifiable_basis.rows() != n) return {kInf, kInf};
  // Whitened residuals: C = S V diag(1 / sigma^2) V^T S in SI units; G = S V diag(1 / sigma).
  Eigen::MatrixXd G = o.column_scale.asDiagonal() * o.identifiable_basis;
  for (int c = 0; c < o.rank; ++c) G.col(c) /= o.singular_values[c];
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  // E: the end points' errors per unit whitened noise, 3 rows per configuration; the predicted
  // mean squared error is ||E||_F^2 / M (E z with z ~ N(0, I)).
  Eigen::MatrixXd E(3 * configurations, o.rank);
  Eigen::MatrixXd S;  // the gauge's motions of the end points, when one is removed
  const int gauge_columns = gauge == PredictionGauge::kRaw     ? 0
                            : gauge == PredictionGauge::kRigid ? 6
                                                               : 7;
  if (gauge_columns > 0) S.resize(3 * configurations, gauge_columns);
  for (int m = 0; m < configurations; ++m) {
    JointVector q(passive.num_joints());
    for (int j = 0; j < q.size(); ++j) {
      const JointLimits& l = passive.links[j].limits;
      q[j] = l.lower + u01(rng) * (l.upper - l.lower);
    }
    const ParameterJacobian J = IdentificationJacobian(passive, q);
    E.middleRows<3>(3 * m) = J.topRows<3>() * G;
    if (gauge_columns > 0) {
      // A small motion t + w x p (+ s p) moves the end point p by [I, -[p x], p] (t, w, s).
      const Vector3 p = EndPose(passive, q).translation();
      auto rows = S.middleRows<3>(3 * m);
      rows.leftCols<3>().setIdentity();
      rows.col(3) << 0.0, p.z(), -p.y();
      rows.col(4) << -p.z(), 0.0, p.x();
      rows.col(5) << p.y(), -p.x(), 0.0;
      if (gauge_columns == 7) rows.col(6) = p;
    }
  }
  const double raw = std::sqrt(E.squaredNorm() / configurations);
  if (gauge_columns > 0) {
    // Least-squares removal of the gauge's span from every column of E (all configurations
    // together, as a gauge fit over the scored configurations does).
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(S);
    const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(S.rows(), S.cols());
    E -= Q * (Q.transpose() * E);
  }
  return {std::sqrt(E.squaredNorm() / configurations), raw};
}

double PredictedPositionError(const KinematicModel& passive, const std::vector<PlannedAxis>& axes,
                              double rank_tolerance, int configurations, std::uint64_t seed,
                              PredictionGauge gauge) {
  return PredictedErrorAndRaw(passive, axes, rank_tolerance, configurations, seed, gauge).first;
}

double PoseSetFitness(const KinematicModel& passive,
                      const std::vector<std::vector<JointVector>>& q_passive,
                      const std::vector<Vector3>& directions, double rank_tolerance) {
  std::vector<AxisSample> samples;
  for (size_t k = 0; k < q_passive.size(); ++k) {
    for (const JointVector& q : q_passive[k]) {
      AxisSample s;
      s.axis = static_cast<int>(k);
      s.q = q;
      samples.push_back(s);
    }
  }
  const MisalignedErrorStack stack = StackMisalignedErrors(passive, samples, directions);
  // The singular values alone (AnalyseObservability's arithmetic without bases and names).
  const SingularValuesAndRank report =
      ObservabilitySingularValues(ProfiledPhi(stack), GeometricColumnScale(passive),
                                  rank_tolerance, LineConstraintInvariants(passive));
  const std::vector<double> sv(report.singular_values.begin(),
                               report.singular_values.begin() + report.rank);
  const double o1 = ObservabilityIndexO1(sv);  // eq. 34
  return o1 > 0.0 ? 1.0 / o1 : kInf;           // eq. 39
}

PosePlanResult PlanCalibrationPoses(const KinematicModel& active, const KinematicModel& passive,
                                    const Transform& X_BaBp, const Transform& X_FC,
                                    const PosePlannerOptions& options) {
  ValidatePosePlannerOptions(options);
  ValidateModel(active, "active model");
  ValidateModel(passive, "passive model");
  const auto check_seed = [](const JointVector& seed, const KinematicModel& m, const char* what) {
    if (seed.size() == 0) return;
    TWIN_REQUIRE(seed.size() == m.num_joints() && seed.allFinite(),
                 std::string(what) + " must hold " + std::to_string(m.num_joints()) +
                     " finite angles, got " + std::to_string(seed.size()));
  };
  check_seed(options.active_ik_seed, active, "active_ik_seed");
  check_seed(options.passive_ik_seed, passive, "passive_ik_seed");
  PosePlanResult result;
  const PosePlannerOptions& o = options;

  // C4/C5 with eq. 38: D .. D + (p-1) D_step must lie in [D_min, min(D_max, planned max)].
  const double d_hi = std::min(o.max_distance, o.planning_max_distance) -
                      (o.positions_per_axis - 1) * o.distance_step;
  if (d_hi < o.min_distance) {
    std::ostringstream s;
    s << "distance window empty: " << o.positions_per_axis << " positions " << o.distance_step
      << " m apart starting at D_min = " << o.min_distance
      << " m exceed min(max_distance, planning_max_distance) = "
      << std::min(o.max_distance, o.planning_max_distance) << " m (C4/C5)";
    result.reason = s.str();
    return result;
  }

  Planner pl;
  pl.active = FlangeModel(active);
  pl.passive = passive;
  pl.active_trig = ChainTrig(pl.active);
  pl.passive_trig = ChainTrig(pl.passive);
  pl.X_BaBp = X_BaBp;
  pl.X_BpBa = X_BaBp.inverse();
  pl.X_CF = X_FC.inverse();
  pl.o = o;
  // A start pose seeds the IK to keep each axis in its branch: a random restart would leave it.
  pl.ik = o.ik;
  if (o.active_ik_seed.size() || o.passive_ik_seed.size()) pl.ik.random_restarts = 0;
  if (o.closed_form_ik) {
    std::string why;  // without the structure: the iterative solver, nothing to report
    pl.active_ik = SphericalWristIk::For(pl.active, &why);
    pl.passive_ik = SphericalWristIk::For(pl.passive, &why);
  }
  pl.z = Vector3::UnitZ();
  const Vector3 p_BpBa = pl.X_BpBa.translation();
  Vector3 to_bp = -p_BpBa;
  to_bp.z() = 0.0;
  pl.h = to_bp.norm() > 1e-9 ? to_bp.normalized() : Vector3::UnitX();
  pl.s = pl.z.cross(pl.h);
  pl.dim = kAxisHead + kPerPosition * o.positions_per_axis;
  pl.lo.resize(pl.dim);
  pl.hi.resize(pl.dim);
  const Vector3 centre = p_BpBa + o.camera_reach * pl.h + o.camera_height * pl.z;
  const double e = o.camera_region_half_extent;
  const double tilt = 0.99 * o.max_visibility_angle / std::sqrt(2.0);  // |(a, b)| < C3 limit
  for (int i = 0; i < 3; ++i) {
    pl.lo(i) = centre(i) - e;
    pl.hi(i) = centre(i) + e;
  }
  pl.lo.segment<2>(3).setConstant(-o.axis_cone_half_angle);
  pl.hi.segment<2>(3).setConstant(o.axis_cone_half_angle);
  pl.lo(5) = -kPi;
  pl.hi(5) = kPi;
  // 1 um inside [D_min, D_max]: the IK tolerance (1e-7 m) must not push a bound pose out.
  pl.lo(6) = o.min_distance + 1e-6;
  pl.hi(6) = std::max(pl.lo(6), d_hi - 1e-6);
  for (int i = 0; i < o.positions_per_axis; ++i) {
    const int b = kAxisHead + kPerPosition * i;
    pl.lo.segment<2>(b).setConstant(-tilt);
    pl.hi.segment<2>(b).setConstant(tilt);
    pl.lo(b + 2) = -kPi;
    pl.hi(b + 2) = kPi;
  }
  const Eigen::VectorXd range = pl.hi - pl.lo;
  const Eigen::VectorXd v_max = o.max_velocity_fraction * range;
  const int q = o.num_axes;

  // One PSO run (eq. 35-41); runs are independent (own seed), so they run in parallel.
  struct RunOutput {
    std::vector<double> history;
    std::vector<PlannedAxis> axes;
    double best = kInf;
    RejectionCounts rejections;
    int evaluations = 0;
    std::string failure;  // non-empty: no feasible start
  };
  auto run_swarm = [&](int run) {
    RunOutput out;
    std::seed_seq seq{static_cast<std::uint32_t>(o.seed), static_cast<std::uint32_t>(o.seed >> 32),
                      static_cast<std::uint32_t>(run)};
    std::mt19937_64 rng(seq);
    std::uniform_real_distribution<double> u01(0.0, 1.0);

    // A random sub-particle for axis k of p, redrawn until feasible (step 1 and 3).
    auto draw = [&](Particle* p, int k, int attempts) {
      Eigen::VectorXd x(pl.dim);
      for (int a = 0; a < attempts; ++a) {
        for (int i = 0; i < pl.dim; ++i) x(i) = pl.lo(i) + u01(rng) * range(i);
        ++out.evaluations;
        const Cause c = pl.Evaluate(x.data(), &p->axes[k]);
        if (c == Cause::kNone) {
          p->x.segment(k * pl.dim, pl.dim) = x;
          return true;
        }
        Count(c, &out.rejections);
      }
      return false;
    };

    std::vector<Particle> swarm(o.swarm_size);
    Eigen::VectorXd g_x;
    std::vector<PlannedAxis> g_axes;
    double g_f = kInf;
    for (Particle& p : swarm) {
      p.x.setZero(q * pl.dim);
      p.v.setZero(q * pl.dim);
      p.axes.resize(q);
      for (int k = 0; k < q; ++k) {
        if (!draw(&p, k, o.max_draws_per_axis)) {
          std::ostringstream s;
          s << "no feasible pose for axis " << k << " of run " << run << " in "
            << o.max_draws_per_axis << " draws";
          out.failure = s.str();
          return out;
        }
      }
      p.f = pl.Fitness(p.axes);
      p.best_x = p.x;
      p.best_axes = p.axes;
      p.best_f = p.f;
      if (p.f < g_f) {
        g_f = p.f;
        g_x = p.x;
        g_axes = p.axes;
      }
    }
    if (g_x.size() == 0) {  // every fitness infinite: follow the first particle
      g_x = swarm[0].x;
      g_axes = swarm[0].axes;
    }
    out.history.push_back(g_f);

    for (int it = 0; it < o.iterations; ++it) {
      if (o.cancel && o.cancel->load()) {
        out.failure = "cancelled";
        return out;
      }
      for (Particle& p : swarm) {
        const Eigen::VectorXd x_old = p.x;
        const std::vector<PlannedAxis> axes_old = p.axes;
        for (int i = 0; i < p.x.size(); ++i) {  // eq. 40-41
          const double r1 = u01(rng), r2 = u01(rng);
          const int j = i % pl.dim;
          double vi = o.inertia * p.v(i) + o.learning_personal * r1 * (p.best_x(i) - p.x(i)) +
                      o.learning_global * r2 * (g_x(i) - p.x(i));
          vi = std::clamp(vi, -v_max(j), v_max(j));
          p.v(i) = vi;
          p.x(i) = std::clamp(p.x(i) + vi, pl.lo(j), pl.hi(j));
        }
        for (int k = 0; k < q; ++k) {  // step 3: infeasible sub-particles are redrawn
          ++out.evaluations;
          const Cause c = pl.Evaluate(p.x.data() + k * pl.dim, &p.axes[k]);
          if (c == Cause::kNone) continue;
          Count(c, &out.rejections);
          if (draw(&p, k, o.redraws_after_update)) continue;
          p.x.segment(k * pl.dim, pl.dim) = x_old.segment(k * pl.dim, pl.dim);
          p.v.segment(k * pl.dim, pl.dim).setZero();
          p.axes[k] = axes_old[k];
        }
        p.f = pl.Fitness(p.axes);
        if (p.f < p.best_f) {
          p.best_f = p.f;
          p.best_x = p.x;
          p.best_axes = p.axes;
        }
        if (p.f < g_f) {
          g_f = p.f;
          g_x = p.x;
          g_axes = p.axes;
        }
      }
      out.history.push_back(g_f);
    }
    out.best = g_f;
    out.axes = g_axes;
    return out;
  };

  std::vector<RunOutput> runs(o.runs);
  const int threads =
      std::max(1, std::min(o.threads > 0 ? o.threads : UsableCpuCount(), o.runs));
  std::atomic<int> next{0};
  auto worker = [&] {
    for (int r = next++; r < o.runs; r = next++) runs[r] = run_swarm(r);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();

  double best_overall = kInf;
  for (int run = 0; run < o.runs; ++run) {
    RunOutput& r = runs[run];
    RejectionCounts& c = result.rejections;
    c.active_ik += r.rejections.active_ik;
    c.passive_ik += r.rejections.passive_ik;
    c.c1_joint_limits += r.rejections.c1_joint_limits;
    c.c2_singularity += r.rejections.c2_singularity;
    c.c3_visibility += r.rejections.c3_visibility;
    c.c4_min_distance += r.rejections.c4_min_distance;
    c.c5_max_distance += r.rejections.c5_max_distance;
    result.evaluations += r.evaluations;
    if (!r.failure.empty()) break;  // counts as if the runs had run one after the other
  }
  for (int run = 0; run < o.runs; ++run) {  // the first failing run decides, as if sequential
    if (!runs[run].failure.empty()) {
      result.status = PosePlannerStatus::kNoFeasiblePoses;
      result.reason = runs[run].failure + "; " + CountsText(result.rejections);
      result.axes.clear();
      return result;
    }
  }
  double best_predicted = kInf;
  for (int run = 0; run < o.runs; ++run) {
    result.fitness_history.push_back(runs[run].history);
    result.run_fitness.push_back(runs[run].best);
    double predicted = kInf, predicted_similarity = kInf;
    if (std::isfinite(runs[run].best)) {
      // A feasible plan has >= 3 positions on every axis, which the identification accepts:
      // a refusal would be our bug, and it propagates rather than becoming "no prediction".
      std::tie(predicted_similarity, predicted) = PredictedErrorAndRaw(
          passive, runs[run].axes, o.rank_tolerance, o.prediction_configurations,
          o.prediction_seed, PredictionGauge::kSimilarity);
    }
    result.run_predicted_error.push_back(predicted);
    result.run_predicted_similarity_error.push_back(predicted_similarity);
    const bool better = o.select_run == PosePlannerOptions::RunSelection::kPredictedError
                            ? predicted < best_predicted
                            : runs[run].best < best_overall;
    if (better || result.best_run < 0) {
      best_overall = runs[run].best;
      best_predicted = predicted;
      result.best_run = run;
      result.axes = runs[run].axes;
    }
  }
  result.best_fitness = best_overall;
  if (!std::isfinite(best_overall)) {
    result.reason = "feasible poses found, but O1 = 0 for all of them (unidentifiable set)";
    result.axes.clear();
    return result;
  }
  result.status = PosePlannerStatus::kSuccess;
  return result;
}

}  // namespace twin
