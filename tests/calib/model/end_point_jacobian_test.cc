// The analytic end-point Jacobian (used by every identification for speed) equals the autodiff
// of the one templated forward kinematics, with and without error terms, for six- and
// seven-joint chains.
#include "calib/model/end_point_jacobian.h"

#include <random>

#include <gtest/gtest.h>

#include "test_models.h"

namespace twin {
namespace {

MeasurementContext Context(const KinematicModel& m, std::mt19937_64& rng) {
  MeasurementContext c;
  c.q = testing::RandomJoints(m, rng);
  c.approach = JointVector::Ones(m.num_joints());
  c.approach(1) = -1.0;
  c.time_s = 1800.0;
  c.temperature_delta_K = 7.5;
  return c;
}

TEST(EndPointJacobian, AnalyticEqualsAutodiffWithJointAndLengthTerms) {
  std::mt19937_64 rng(61);
  for (const KinematicModel& base : {testing::ReinovoLikeModel(), testing::SevenJointModel()}) {
    const KinematicModel chain = testing::Perturbed(base, rng, 0.01, 0.05);
    RobotModel m = MakeRobotModel(chain);
    m = WithTerm(m, MakeErrorTerm({"transmission_error", 2, {1, 2}}, chain, chain.name));
    m = WithTerm(m, MakeErrorTerm({"backlash", 1, {}}, chain, chain.name));
    m = WithTerm(m, MakeErrorTerm({"thermal_growth", -1, {}}, chain, chain.name));
    m = WithTerm(m, MakeErrorTerm({"thermal_drift", -1, {}}, chain, chain.name));
    m.term_values << 1e-3, -2e-3, 5e-4, 1e-3, -1e-3, 2e-5, 3e-8;
    ASSERT_TRUE(AnalyticEndPointJacobian(m));
    const Eigen::VectorXd p = GetParameters(m);
    for (int trial = 0; trial < 20; ++trial) {
      const MeasurementContext c = Context(chain, rng);
      Vector3 pa, pd;
      PointJacobian Ja, Jd;
      EndPointJacobian(m, p.data(), c, &pa, &Ja);
      EndPointJacobianAutodiff(m, p.data(), c, &pd, &Jd);
      // 1e-12: two exact derivatives of the same function; entries below ~2 m per unit (the
      // drift column: up to 1800 s times a ~1 m reach, compared relatively).
      EXPECT_LT((pa - pd).norm(), 1e-13);
      for (int k = 0; k < Ja.cols(); ++k) {
        EXPECT_LT((Ja.col(k) - Jd.col(k)).norm(), 1e-12 * std::max(1.0, Jd.col(k).norm()))
            << "column " << k;
      }
    }
  }
}

TEST(EndPointJacobian, CoupledTermsUseAutodiff) {
  const KinematicModel chain = testing::ReinovoLikeModel();
  RobotModel m = WithTerm(MakeRobotModel(chain),
                          MakeErrorTerm({"joint_compliance", 1, {}}, chain, "r1"));
  EXPECT_FALSE(AnalyticEndPointJacobian(m));
  m = WithTerm(MakeRobotModel(chain), MakeErrorTerm({"mount_deflection", -1, {}}, chain, "r1"));
  EXPECT_FALSE(AnalyticEndPointJacobian(m));
}

}  // namespace
}  // namespace twin
