// The estimator's robot model: its forward kinematics without terms is the chain's, gravity
// torques are the derivative of the potential energy, the compliance sag solves its fixed
// point, and the layout maps names to the flat vector and back.
#include "calib/model/robot_model.h"

#include <random>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "calib/model/parameter_layout.h"
#include "test_models.h"

namespace twin {
namespace {

using testing::Perturbed;
using testing::RandomJoints;
using testing::ReinovoLikeModel;

TEST(RobotModel, WithoutTermsItIsTheChainsForwardKinematics) {
  std::mt19937_64 rng(31);
  for (int trial = 0; trial < 20; ++trial) {
    const KinematicModel chain = Perturbed(ReinovoLikeModel(), rng, 0.01, 0.05);
    const RobotModel model = MakeRobotModel(chain);
    const JointVector q = RandomJoints(chain, rng);
    // 1e-14: the same operations in the same order; only the final Isometry conversion differs.
    EXPECT_LT((EndPose(model, ContextOf(q)).matrix() - EndPose(chain, q).matrix()).norm(), 1e-14);
  }
}

// A thermal growth k dT grows d and a of every joint link and not the tool link (what the
// flange carries): the model's end pose at dT is the chain's with the joint links' lengths
// times 1 + k dT and the tool link as it is. Written here from that statement, not from the
// model's code; 1e-12 m: a few operations on metre values.
TEST(RobotModel, AThermalGrowthGrowsTheJointLinksAndNotTheToolLink) {
  std::mt19937_64 rng(37);
  const KinematicModel chain = Perturbed(ReinovoLikeModel(), rng, 0.01, 0.05);
  ASSERT_GT(std::abs(chain.tool().dh.a) + std::abs(chain.tool().dh.d), 0.01);  // a real tool
  RobotModel m = WithTerm(MakeRobotModel(chain), MakeErrorTerm({"thermal_growth", -1, {}},
                                                               chain, chain.name));
  m.term_values << 2.3e-5;
  const double scale = 1.0 + 2.3e-5 * 20.0;
  KinematicModel grown = chain;
  for (int i = 0; i < chain.num_joints(); ++i) {
    grown.links[i].dh.d *= scale;
    grown.links[i].dh.a *= scale;
  }
  for (int trial = 0; trial < 10; ++trial) {
    MeasurementContext c = ContextOf(RandomJoints(chain, rng));
    c.temperature_delta_K = 20.0;
    EXPECT_LT((EndPose(m, c).translation() - EndPose(grown, c.q).translation()).norm(), 1e-12);
  }
}

// Potential energy of the nominal masses in gravity g g_B at link angles q [J].
double PotentialEnergy(const RobotModel& m, const JointVector& q) {
  const FrameSet f = ForwardKinematics(m.chain, q);
  double V = 0.0;
  for (int j = 0; j < m.chain.num_links(); ++j) {
    const Vector3 c = f.X_BL[j + 1] * m.chain.links[j].inertia.p_LiCom;
    V -= m.chain.links[j].inertia.mass * m.gravity * m.gravity_B.dot(c);
  }
  return V;
}

TEST(RobotModel, GravityTorquesAreMinusTheGradientOfThePotentialEnergy) {
  std::mt19937_64 rng(32);
  const RobotModel m = MakeRobotModel(ReinovoLikeModel());
  for (int trial = 0; trial < 20; ++trial) {
    const JointVector q = RandomJoints(m.chain, rng);
    const Eigen::VectorXd tau = GravityTorques(m, q);
    for (int i = 0; i < 6; ++i) {
      JointVector qp = q, qm = q;
      qp(i) += 1e-6;
      qm(i) -= 1e-6;
      const double fd = -(PotentialEnergy(m, qp) - PotentialEnergy(m, qm)) / 2e-6;
      // 1e-6 N m: central differences of a potential of ~100 J err by ~1e-12 J h^2 curvature
      // plus 1e-14 J / 1e-6 rounding = 1e-8 N m; a wrong lever arm errs by > 0.1 N m.
      EXPECT_NEAR(tau(i), fd, 1e-6) << "joint " << i + 1;
    }
    EXPECT_NEAR(tau(0), 0.0, 1e-12) << "joint 1 turns about gravity";
  }
}

TEST(RobotModel, ComplianceSagSolvesItsFixedPoint) {
  std::mt19937_64 rng(33);
  const KinematicModel chain = ReinovoLikeModel();
  RobotModel m = MakeRobotModel(chain);
  for (int j : {1, 2, 4}) m = WithTerm(m, MakeErrorTerm({"joint_compliance", j, {}}, chain, "r1"));
  m.term_values << 1e-4, 2e-4, 3e-4;  // soft joints (k = 3300 to 10000 N m/rad)
  const Eigen::VectorXd p = GetParameters(m);
  for (int trial = 0; trial < 20; ++trial) {
    const MeasurementContext c = ContextOf(RandomJoints(chain, rng));
    JointVector q(6);
    double s = 0;
    LinkAnglesT<double>(m, p.data(), c, q.data(), &s);
    const Eigen::VectorXd tau = GravityTorques(m, q);
    JointVector expected = c.q;
    expected(1) += 1e-4 * tau(1);
    expected(2) += 2e-4 * tau(2);
    expected(4) += 3e-4 * tau(4);
    // 1e-10 rad: kSagIterations leave (c dtau/dq)^4 ~ (3e-4 * 60)^4 = 1e-7 of a ~1e-2 rad sag.
    EXPECT_LT((q - expected).cwiseAbs().maxCoeff(), 1e-10);
    EXPECT_GT((q - c.q).cwiseAbs().maxCoeff(), 1e-4) << "the pose loads a compliant joint";
  }
}

TEST(RobotModel, ComplianceSagStopsEarlyWithItsDerivativeConverged) {
  // The sag iteration stops once the angles stop moving (kSagTolerance); the derivative a Jet
  // carries must have converged with them. At the fixed point q3 = q3_0 + c tau3(q), the
  // implicit function theorem gives dq3/dc = tau3 / (1 - c dtau3/dq3) at the converged q. A
  // stiff joint (1e-7 rad/(N m): the iteration stops after three rounds) and a zero compliance
  // (after one: the start of a candidate in model discovery).
  std::mt19937_64 rng(35);
  const KinematicModel chain = ReinovoLikeModel();
  RobotModel m =
      WithTerm(MakeRobotModel(chain), MakeErrorTerm({"joint_compliance", 2, {}}, chain, "r1"));
  for (double c : {0.0, 1e-7}) {
    m.term_values << c;
    const Eigen::VectorXd p = GetParameters(m);
    std::vector<Jet> pj(p.size());
    for (int i = 0; i < p.size(); ++i) pj[i] = Jet(p(i));
    pj.back().v(0) = 1.0;  // d/dc (twin::Jet, the terms' Jet type; its other slots stay 0)
    for (int trial = 0; trial < 10; ++trial) {
      const MeasurementContext ctx = ContextOf(RandomJoints(chain, rng));
      Jet qj[kMaxJoints], sj;
      LinkAnglesT<Jet>(m, pj.data(), ctx, qj, &sj);
      JointVector q(6);
      for (int i = 0; i < 6; ++i) q(i) = qj[i].a;
      const double h = 1e-6;
      JointVector plus = q, minus = q;
      plus(2) += h;
      minus(2) -= h;
      const double slope = (GravityTorques(m, plus)(2) - GravityTorques(m, minus)(2)) / (2 * h);
      const double expected = GravityTorques(m, q)(2) / (1.0 - c * slope);
      // Stopping after one round at c = 1e-7 would leave c (tau3 slope + tau3 dtau3/dq3) ~ 1e-3
      // N m of error (tau3 ~ 50 N m, slopes ~ 100 N m/rad); the central difference's own error
      // is ~1e-9 N m/rad times c. 1e-6 N m separates the two.
      EXPECT_NEAR(qj[2].v(0), expected, 1e-6) << "c " << c << ", trial " << trial;
      EXPECT_GT(std::abs(expected), 1e-3) << "the pose loads joint 3";
    }
  }
}

TEST(RobotModel, MountDeflectionMovesTheEndPointAlongGravityInTheFlange) {
  const KinematicModel chain = ReinovoLikeModel();
  RobotModel m = WithTerm(MakeRobotModel(chain), MakeErrorTerm({"mount_deflection", -1, {}},
                                                               chain, "r1"));
  m.term_values << 1e-4, 2e-4, 3e-4;
  const JointVector q = MidRange(chain);
  const FrameSet f = ForwardKinematics(chain, q);
  const Vector3 g_F = f.flange().linear().transpose() * m.gravity_B;
  const Vector3 expected =
      f.X_BE.translation() + f.flange().linear() * Vector3(1e-4, 2e-4, 3e-4).cwiseProduct(g_F);
  EXPECT_LT((EndPose(m, ContextOf(q)).translation() - expected).norm(), 1e-15);
}

TEST(ParameterLayout, NamesBlocksAndTheFlatVectorRoundTrip) {
  const KinematicModel chain = ReinovoLikeModel();
  RobotModel m = MakeRobotModel(chain);
  m = WithTerm(m, MakeErrorTerm({"joint_compliance", 1, {}}, chain, chain.name));
  m = WithTerm(m, MakeErrorTerm({"transmission_error", 3, {2}}, chain, chain.name));
  const ParameterLayout layout(m);
  ASSERT_EQ(layout.size(), 35 + 1 + 2);
  EXPECT_EQ(layout.geometry_size(), 35);
  EXPECT_EQ(layout[0].name, "r1.link1.theta");
  EXPECT_EQ(layout[35].name, "r1.joint2.compliance");
  EXPECT_EQ(layout[36].name, "r1.joint4.harmonic2.sin");
  EXPECT_EQ(layout.Find("r1.joint4.harmonic2.cos"), 37);
  ASSERT_EQ(layout.blocks().size(), 3u);
  EXPECT_EQ(layout.blocks()[1].name, "joint_compliance (joint 2)");
  EXPECT_EQ(layout.blocks()[2].begin, 36);
  EXPECT_EQ(layout[1].unit, "m");
  EXPECT_EQ(layout[35].unit, "rad/(N m)");
  // Callers build the names from the layout: an unknown one is our bug.
  EXPECT_THROW(layout.Find("r1.joint9.compliance"), PreconditionError);
  Eigen::VectorXd p = GetParameters(m);
  p(36) = 1e-4;
  p(2) += 1e-3;
  const RobotModel m2 = WithParameters(m, p);
  EXPECT_EQ(GetParameters(m2), p);
  EXPECT_EQ(m2.term_values(1), 1e-4);
  EXPECT_EQ(m2.chain.links[0].dh.a, chain.links[0].dh.a + 1e-3);
}

}  // namespace
}  // namespace twin
