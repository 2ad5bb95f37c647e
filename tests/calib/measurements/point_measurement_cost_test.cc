// The measurement costs (end point Jacobian joined with the measurement functor's autodiff)
// against numeric differentiation by ceres::GradientChecker, for the optical-axis line, the
// line with depth and the tracker point, with a model carrying error terms.
#include "calib/measurements/point_measurement_cost.h"

#include <random>

#include <gtest/gtest.h>

#include "calib/measurements/optical_axis_residual.h"
#include "calib/measurements/tracker_point_residual.h"
#include "calib/model/parameter_layout.h"
#include "test_models.h"

namespace twin {
namespace {

RobotModel Model() {
  std::mt19937_64 rng(71);
  const KinematicModel chain = testing::Perturbed(testing::ReinovoLikeModel(), rng, 0.005, 0.01);
  RobotModel m = MakeRobotModel(chain);
  m = WithTerm(m, MakeErrorTerm({"transmission_error", 3, {2}}, chain, "r1"));
  m = WithTerm(m, MakeErrorTerm({"joint_compliance", 1, {}}, chain, "r1"));
  m.term_values << 2e-4, -1e-4, 3e-5;
  return m;
}

// Central differences of every block with steps of 1e-6 of each parameter's scale (the model's
// layout scales; 1e-6 for the nuisance), against the cost's Jacobians. They err by ~(h/scale)^2
// of the curvature plus rounding ~1e-16 |r| / h; 1e-6 of the largest entry of each column
// separates a right Jacobian from a wrong one (a missing chain-rule factor errs by O(1)).
// (Ceres' GradientChecker steps relative to the value, 3e-11 for a compliance of 3e-5 rad/(N m),
// where rounding of residuals of 1e5 swamps the difference.)
void ExpectJacobiansMatchNumeric(const ceres::CostFunction& cost, const RobotModel& m,
                                 std::vector<double*> blocks) {
  const int rows = cost.num_residuals();
  const std::vector<int32_t>& sizes = cost.parameter_block_sizes();
  std::vector<std::vector<double>> jac(sizes.size());
  std::vector<double*> jp;
  for (size_t b = 0; b < sizes.size(); ++b) {
    jac[b].resize(rows * sizes[b]);
    jp.push_back(jac[b].data());
  }
  std::vector<double> r(rows), rp(rows), rm(rows);
  ASSERT_TRUE(cost.Evaluate(blocks.data(), r.data(), jp.data()));
  const Eigen::VectorXd scales = ParameterLayout(m).scales();
  for (size_t b = 0; b < sizes.size(); ++b) {
    for (int j = 0; j < sizes[b]; ++j) {
      const double h = 1e-6 * (b == 0 ? scales(j) : 1.0);
      const double keep = blocks[b][j];
      blocks[b][j] = keep + h;
      ASSERT_TRUE(cost.Evaluate(blocks.data(), rp.data(), nullptr));
      blocks[b][j] = keep - h;
      ASSERT_TRUE(cost.Evaluate(blocks.data(), rm.data(), nullptr));
      blocks[b][j] = keep;
      double largest = 0.0;
      for (int i = 0; i < rows; ++i) largest = std::max(largest, std::abs(jac[b][i * sizes[b] + j]));
      for (int i = 0; i < rows; ++i) {
        const double fd = (rp[i] - rm[i]) / (2 * h);
        // Plus 1e-4 absolute: rounding of weighted residuals up to ~1e5 is ~1e-11, over 2h.
        EXPECT_NEAR(jac[b][i * sizes[b] + j], fd, 1e-6 * largest + 1e-4)
            << "block " << b << " column " << j << " row " << i;
      }
    }
  }
}

TEST(PointMeasurementCost, OpticalAxisLineMatchesNumericDerivatives) {
  const RobotModel m = Model();
  const MeasurementContext c = ContextOf(MidRange(m.chain));
  const double weight = 5e4;
  Eigen::Matrix<double, 3, 2> N;
  N << 1, 0, 0, 1, 0, 0;
  PointMeasurementCost<OpticalAxisLine, 3, 2, 3> cost(
      m, c, new OpticalAxisLine{Vector3(1e-5, 0, 2e-5), Vector3(0.4, 0.1, 0.3), N, weight});
  Eigen::VectorXd params = GetParameters(m);
  double s[2] = {0.001, -0.002};
  double mu[3] = {0.1, 0.2, 0.97};
  ExpectJacobiansMatchNumeric(cost, m, {params.data(), s, mu});
}

TEST(PointMeasurementCost, OpticalAxisLineWithDepthMatchesNumericDerivatives) {
  const RobotModel m = Model();
  const MeasurementContext c = ContextOf(MidRange(m.chain));
  const double weight = 5e4, depth_weight = 1e4;
  Eigen::Matrix<double, 3, 2> N;
  N << 0, 0, 1, 0, 0, 1;
  const OpticalAxisLine line{Vector3::Zero(), Vector3(0.3, -0.2, 0.4), N, weight};
  PointMeasurementCost<OpticalAxisLineDepth, 4, 2, 3, 1> cost(
      m, c, new OpticalAxisLineDepth{line, 0.45, depth_weight});
  Eigen::VectorXd params = GetParameters(m);
  double s[2] = {0.0, 0.003};
  double mu[3] = {0.9, 0.3, 0.1};
  double t[1] = {-0.2};
  ExpectJacobiansMatchNumeric(cost, m, {params.data(), s, mu, t});
}

TEST(PointMeasurementCost, TrackerPointMatchesNumericDerivatives) {
  const RobotModel m = Model();
  const MeasurementContext c = ContextOf(MidRange(m.chain));
  const double weight = 1.0;
  PointMeasurementCost<TrackerPointResidual, 3, 4, 3> cost(
      m, c, new TrackerPointResidual{Vector3(1.5, -0.3, 0.2), 1e-5, weight});
  Eigen::VectorXd params = GetParameters(m);
  Eigen::Quaterniond q(Eigen::AngleAxisd(0.4, Vector3(1, 2, 3).normalized()));
  double qb[4] = {q.x(), q.y(), q.z(), q.w()};
  double tb[3] = {-1.0, 0.5, 0.2};
  ExpectJacobiansMatchNumeric(cost, m, {params.data(), qb, tb});
}

}  // namespace
}  // namespace twin
