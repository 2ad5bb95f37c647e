#include "bench/scoring/calibration_scoring.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <Eigen/Geometry>

#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "calib/model/parameters.h"

namespace twin {
namespace {

PositionErrorStats Stats(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b) {
  PositionErrorStats s;
  const Eigen::VectorXd d = (a - b).colwise().norm();
  s.rms = std::sqrt(d.squaredNorm() / static_cast<double>(d.size()));
  s.max = d.maxCoeff();
  return s;
}

Eigen::Matrix3Xd ToMatrix(const std::vector<Vector3>& points) {
  Eigen::Matrix3Xd m(3, points.size());
  for (size_t i = 0; i < points.size(); ++i) m.col(i) = points[i];
  return m;
}

// End points of the three models at the same configurations.
struct EndPoints {
  std::vector<Vector3> nominal, identified, truth;
};
EndPoints EndPointsAt(const KinematicModel& nominal, const KinematicModel& identified,
                      const KinematicModel& truth, const std::vector<JointVector>& qs) {
  EndPoints p;
  for (const JointVector& q : qs) {
    p.nominal.push_back(EndPose(nominal, q).translation());
    p.identified.push_back(EndPose(identified, q).translation());
    p.truth.push_back(EndPose(truth, q).translation());
  }
  return p;
}

}  // namespace

GaugeErrors CompareInGauges(const std::vector<Vector3>& model, const std::vector<Vector3>& truth,
                            double* similarity_scale) {
  if (model.size() != truth.size() || model.size() < 4) {
    throw std::logic_error("CompareInGauges: need >= 4 matching points");
  }
  const Eigen::Matrix3Xd a = ToMatrix(model), b = ToMatrix(truth);
  GaugeErrors g;
  g.raw = Stats(a, b);
  // Umeyama (Eigen): the least-squares rigid / similarity transform taking a onto b.
  const Eigen::Matrix4d T_rigid = Eigen::umeyama(a, b, false);
  const Eigen::Matrix4d T_sim = Eigen::umeyama(a, b, true);
  g.rigid = Stats((T_rigid.topLeftCorner<3, 3>() * a).colwise() + T_rigid.topRightCorner<3, 1>(), b);
  g.similarity = Stats((T_sim.topLeftCorner<3, 3>() * a).colwise() + T_sim.topRightCorner<3, 1>(), b);
  if (similarity_scale) *similarity_scale = T_sim.topLeftCorner<3, 3>().col(0).norm();
  return g;
}

std::vector<JointVector> RandomJointConfigurations(const KinematicModel& model, int n,
                                                   std::uint64_t seed, double margin) {
  JointBox box{JointVector(model.num_joints()), JointVector(model.num_joints())};
  for (int i = 0; i < model.num_joints(); ++i) {
    const JointLimits& l = model.links[i].limits;
    box.lower(i) = l.lower + margin;
    box.upper(i) = std::max(box.lower(i), l.upper - margin);
  }
  return RandomJointConfigurationsIn(box, n, seed);
}

JointBox CoveredJointBox(const std::vector<JointVector>& poses) {
  if (poses.empty()) throw std::logic_error("CoveredJointBox: no poses");
  JointBox box{poses[0], poses[0]};
  for (const JointVector& q : poses) {
    if (q.size() != box.lower.size()) throw std::logic_error("CoveredJointBox: joint counts differ");
    box.lower = box.lower.cwiseMin(q);
    box.upper = box.upper.cwiseMax(q);
  }
  return box;
}

std::vector<JointVector> RandomJointConfigurationsIn(const JointBox& box, int n,
                                                     std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<JointVector> qs;
  for (int c = 0; c < n; ++c) {
    JointVector q(box.lower.size());
    for (int i = 0; i < q.size(); ++i) {
      q(i) = std::uniform_real_distribution<double>(box.lower(i), box.upper(i))(rng);
    }
    qs.push_back(q);
  }
  return qs;
}

RegionScore ScoreRegion(const KinematicModel& nominal, const KinematicModel& identified,
                        const KinematicModel& truth, const JointBox& box, int n,
                        std::uint64_t seed) {
  RegionScore s;
  s.configurations = n;
  const EndPoints p =
      EndPointsAt(nominal, identified, truth, RandomJointConfigurationsIn(box, n, seed));
  s.before = CompareInGauges(p.nominal, p.truth);
  s.after = CompareInGauges(p.identified, p.truth);
  return s;
}

RobotScore EstimatesWithoutTruth(const KinematicModel& nominal, const KinematicModel& identified,
                                 const ObservabilityReport& observability, int configurations,
                                 std::uint64_t seed) {
  // Scored against the identified model itself, then every figure against truth made NaN:
  // the estimated side is computed by the very code that scores a twin's run.
  RobotScore s = ScoreRobot(nominal, identified, identified, observability, configurations, seed);
  constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  for (GaugeErrors* g : {&s.before, &s.after}) {
    for (PositionErrorStats* e : {&g->raw, &g->rigid, &g->similarity}) *e = {kNone, kNone};
  }
  s.scale_true = kNone;
  for (ParameterComparison& p : s.parameters) p.truth = kNone;
  for (double& z : s.combination_true) z = kNone;
  s.combination_rms_error = s.combination_max_error = kNone;
  return s;
}

RobotScore ScoreRobot(const KinematicModel& nominal, const KinematicModel& identified,
                      const KinematicModel& truth, const ObservabilityReport& observability,
                      int configurations, std::uint64_t seed) {
  RobotScore s;
  s.configurations = configurations;
  const EndPoints p =
      EndPointsAt(nominal, identified, truth,
                  RandomJointConfigurations(nominal, configurations, seed, DegToRad(10.0)));
  s.before = CompareInGauges(p.nominal, p.truth);
  s.after = CompareInGauges(p.identified, p.truth);
  // Scale of a model's point cloud relative to the nominal one: the similarity taking the
  // nominal points onto the model's has scale |model| / |nominal|.
  CompareInGauges(p.nominal, p.identified, &s.scale_estimated);
  CompareInGauges(p.nominal, p.truth, &s.scale_true);

  const ParameterVector phi0 = GetParameters(nominal);
  const ParameterVector d_est = GetParameters(identified) - phi0;
  const ParameterVector d_true = GetParameters(truth) - phi0;
  for (int i = 0; i < d_est.size(); ++i) {
    s.parameters.push_back({ParameterName(nominal.name, i), IsLengthParameter(i), d_est(i),
                            d_true(i)});
  }
  // The SVD fixes each basis vector only up to its sign: the sign that makes its largest entry
  // positive, so that trials (and two runs of one trial) report the same coordinates.
  Eigen::MatrixXd V = observability.identifiable_basis;
  for (int j = 0; j < V.cols(); ++j) {
    Eigen::Index i = 0;
    V.col(j).cwiseAbs().maxCoeff(&i);
    if (V(i, j) < 0) V.col(j) = -V.col(j);
  }
  if (V.cols() > 0) {
    const ParameterVector inv_scale = observability.column_scale.cwiseInverse();
    const Eigen::VectorXd ze = V.transpose() * inv_scale.cwiseProduct(d_est);
    const Eigen::VectorXd zt = V.transpose() * inv_scale.cwiseProduct(d_true);
    s.combination_estimated.assign(ze.data(), ze.data() + ze.size());
    s.combination_true.assign(zt.data(), zt.data() + zt.size());
    const Eigen::VectorXd e = ze - zt;
    s.combination_rms_error = std::sqrt(e.squaredNorm() / static_cast<double>(e.size()));
    s.combination_max_error = e.cwiseAbs().maxCoeff();
  }
  return s;
}

}  // namespace twin
