#include "calib/kinematics/forward_kinematics.h"

#include <random>

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include "test_models.h"

namespace twin {
namespace {

using testing::Perturbed;
using testing::RandomJoints;
using testing::ReinovoLikeModel;

// Per-link transform of eq. 2 built from Eigen's elementary rotations and translations.
Eigen::Matrix4d Elementary(const DhParameters& dh, double q) {
  const Eigen::Matrix4d Rz = Transform(Eigen::AngleAxisd(dh.theta_offset + q, Vector3::UnitZ())).matrix();
  const Eigen::Matrix4d Tz = Transform(Eigen::Translation3d(0, 0, dh.d)).matrix();
  const Eigen::Matrix4d Tx = Transform(Eigen::Translation3d(dh.a, 0, 0)).matrix();
  const Eigen::Matrix4d Rx = Transform(Eigen::AngleAxisd(dh.alpha, Vector3::UnitX())).matrix();
  const Eigen::Matrix4d Ry = Transform(Eigen::AngleAxisd(dh.beta, Vector3::UnitY())).matrix();
  return Rz * Tz * Tx * Rx * Ry;
}

// Rotation vector w with R_a ~ exp([w x]) R_b.
Vector3 RotationDifference(const Matrix3& R_a, const Matrix3& R_b) {
  const Eigen::AngleAxisd aa(R_a * R_b.transpose());
  return aa.angle() * aa.axis();
}

TEST(ForwardKinematics, EqualsIndependentCompositionOfLinkTransforms) {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 50; ++trial) {
    const KinematicModel m = Perturbed(ReinovoLikeModel(), rng, 0.01, 0.05);
    const JointVector q = RandomJoints(m, rng);
    const FrameSet f = ForwardKinematics(m, q);
    Eigen::Matrix4d X = m.X_BL0.matrix();
    for (int i = 0; i < 7; ++i) {
      X = X * Elementary(m.links[i].dh, i < 6 ? q(i) : 0.0);
      // 1e-12: a product of at most nine 4x4 matrices with entries below 1.5 in magnitude.
      EXPECT_LT((f.X_BL[i + 1].matrix() - X).norm(), 1e-12) << "frame L" << i + 1;
    }
    X = X * m.X_LtE.matrix();
    EXPECT_LT((f.X_BE.matrix() - X).norm(), 1e-12);
    EXPECT_LT((EndPose(m, q).matrix() - X).norm(), 1e-12);
  }
}

TEST(ForwardKinematics, NominalGeometryHasTheTablesInvariants) {
  // Checks read off the table of models/reinovo_r1.yaml, independent of the FK code path.
  const KinematicModel m = ReinovoLikeModel();
  const FrameSet f = ForwardKinematics(m, ZeroJoints(m));
  EXPECT_NEAR(f.X_BL[1].translation().z(), 0.1365, 1e-15);  // d1
  EXPECT_NEAR(f.X_BL[1].translation().x(), 0.100, 1e-15);   // a1 along x0 at q1 = 0
  // Joints 2 and 3 are parallel (alpha2 = 0).
  EXPECT_NEAR(f.X_BL[1].linear().col(2).dot(f.X_BL[2].linear().col(2)), 1.0, 1e-15);
  // The upper arm a2 = 0.290 separates the two parallel axes.
  EXPECT_NEAR((f.X_BL[2].translation() - f.X_BL[1].translation()).norm(), 0.290, 1e-15);
  // Spherical wrist: axes 4, 5 and 6 meet in one point (a4 = a5 = d5 = 0).
  EXPECT_LT((f.X_BL[4].translation() - f.X_BL[5].translation()).norm(), 1e-15);
}

TEST(IdentificationJacobian, MatchesCentralFiniteDifferences) {
  std::mt19937_64 rng(12);
  constexpr double h = 1e-6;
  for (int trial = 0; trial < 30; ++trial) {
    const KinematicModel m = Perturbed(ReinovoLikeModel(), rng, 0.01, 0.05);
    const JointVector q = RandomJoints(m, rng);
    const auto J = IdentificationJacobian(m, q);
    const ParameterVector p0 = GetParameters(m);
    for (int k = 0; k < 35; ++k) {
      ParameterVector pp = p0, pm = p0;
      pp(k) += h;
      pm(k) -= h;
      const Transform Xp = EndPose(WithParameters(m, pp), q);
      const Transform Xm = EndPose(WithParameters(m, pm), q);
      const Vector3 dp = (Xp.translation() - Xm.translation()) / (2 * h);
      const Vector3 dw = RotationDifference(Xp.linear(), Xm.linear()) / (2 * h);
      // 1e-8: central differences err by h^2/6 * |third derivative| (~1e-12 for a 1 m arm)
      // plus rounding of about 1e-16 / h = 1e-10; 1e-8 leaves a wide margin and is still
      // six orders below a wrong column (whose entries are of order 0.1 to 1).
      EXPECT_LT((J.block<3, 1>(0, k) - dp).norm(), 1e-8) << ParameterName(m.name, k);
      EXPECT_LT((J.block<3, 1>(3, k) - dw).norm(), 1e-8) << ParameterName(m.name, k);
    }
  }
}

TEST(IdentificationJacobian, EqualsAutodiffOfTheTemplatedForwardKinematics) {
  // The analytic Jacobian is kept for the pose planner's speed (twinbench benchmark-kinematics
  // prints the ratio); it must equal the derivative of the one templated FK, for six- and
  // seven-joint chains.
  std::mt19937_64 rng(14);
  for (const KinematicModel& base : {ReinovoLikeModel(), testing::SevenJointModel()}) {
    for (int trial = 0; trial < 10; ++trial) {
      const KinematicModel m = Perturbed(base, rng, 0.01, 0.05);
      const JointVector q = RandomJoints(m, rng);
      const ParameterJacobian J = IdentificationJacobian(m, q);
      const ParameterVector p0 = GetParameters(m);
      using Jet1 = ceres::Jet<double, 1>;
      for (int k = 0; k < m.num_parameters(); ++k) {
        std::vector<Jet1> phi(p0.size());
        for (int i = 0; i < p0.size(); ++i) phi[i] = Jet1(p0(i));
        phi[k].v[0] = 1.0;
        std::vector<Jet1> qj(q.size());
        for (int i = 0; i < q.size(); ++i) qj[i] = Jet1(q(i));
        const RigidT<Jet1> X = ChainEndPoseT<Jet1>(m, phi.data(), qj.data(), Jet1(1.0));
        for (int r = 0; r < 3; ++r) {
          // 1e-12: both are exact derivatives; they differ by rounding only (entries < 2 m).
          EXPECT_NEAR(J(r, k), X.p(r).v[0], 1e-12) << ParameterName(m.name, k);
        }
      }
    }
  }
}

TEST(ForwardKinematics, SevenJointChainEqualsTheCompositionOfItsLinks) {
  std::mt19937_64 rng(15);
  for (int trial = 0; trial < 20; ++trial) {
    const KinematicModel m = Perturbed(testing::SevenJointModel(), rng, 0.01, 0.05);
    const JointVector q = RandomJoints(m, rng);
    const FrameSet f = ForwardKinematics(m, q);
    Eigen::Matrix4d X = m.X_BL0.matrix();
    for (int i = 0; i < m.num_links(); ++i) {
      X = X * Elementary(m.links[i].dh, i < 7 ? q(i) : 0.0);
      // 1e-12: a product of at most ten 4x4 matrices with entries below 1.5 in magnitude.
      EXPECT_LT((f.X_BL[i + 1].matrix() - X).norm(), 1e-12) << "frame L" << i + 1;
    }
    EXPECT_LT((f.X_BE.matrix() - X * m.X_LtE.matrix()).norm(), 1e-12);
  }
}

TEST(ManipulatorJacobian, MatchesCentralFiniteDifferences) {
  std::mt19937_64 rng(13);
  constexpr double h = 1e-6;
  for (int trial = 0; trial < 30; ++trial) {
    const KinematicModel m = Perturbed(ReinovoLikeModel(), rng, 0.01, 0.05);
    const JointVector q = RandomJoints(m, rng);
    const auto J = ManipulatorJacobian(m, q);
    for (int i = 0; i < 6; ++i) {
      JointVector qp = q, qm = q;
      qp(i) += h;
      qm(i) -= h;
      const Transform Xp = EndPose(m, qp), Xm = EndPose(m, qm);
      const Vector3 dp = (Xp.translation() - Xm.translation()) / (2 * h);
      const Vector3 dw = RotationDifference(Xp.linear(), Xm.linear()) / (2 * h);
      // 1e-8: same finite-difference error budget as the identification Jacobian.
      EXPECT_LT((J.block<3, 1>(0, i) - dp).norm(), 1e-8) << "joint " << i + 1;
      EXPECT_LT((J.block<3, 1>(3, i) - dw).norm(), 1e-8) << "joint " << i + 1;
    }
  }
}

TEST(ForwardKinematics, OnePassGivesTheFramesAndTheEndPoseBitForBit) {
  // FramesAndEndPose replaces an EndPose and a ForwardKinematics call in every IK iteration;
  // IK results (and so the planner's poses) stay identical only if both agree to the bit, with
  // and without the cached cosines of a ChainTrig. A tool link and a non-identity end offset
  // make the end pose's last product count.
  std::mt19937_64 rng(15);
  for (int trial = 0; trial < 50; ++trial) {
    KinematicModel m = Perturbed(ReinovoLikeModel(), rng, 0.01, 0.05);
    m.X_LtE = Transform(Eigen::AngleAxisd(0.3 + 0.01 * trial, Vector3(1, 2, 3).normalized()));
    m.X_LtE.translation() = Vector3(0.01, -0.02, 0.05);
    const JointVector q = RandomJoints(m, rng);
    const ChainTrig trig(m);
    for (const ChainTrig* t : {static_cast<const ChainTrig*>(nullptr), &trig}) {
      FrameSet f;
      const Transform X = FramesAndEndPose(m, q, t, &f);
      const FrameSet g = ForwardKinematics(m, q, t);
      EXPECT_TRUE(X.matrix() == EndPose(m, q, t).matrix()) << "trial " << trial;
      EXPECT_TRUE(f.X_BE.matrix() == g.X_BE.matrix()) << "trial " << trial;
      for (int i = 0; i <= m.num_links(); ++i) {
        EXPECT_TRUE(f.X_BL[i].matrix() == g.X_BL[i].matrix()) << "trial " << trial << " frame " << i;
      }
      const JointJacobian J = ManipulatorJacobian(f);
      EXPECT_TRUE(J == ManipulatorJacobian(m, q, t)) << "trial " << trial;
    }
  }
}

TEST(ManipulatorJacobian, JointColumnsEqualTheThetaColumnsOfTheIdentificationJacobian) {
  // Turning joint i and changing theta_offset_i move the chain identically.
  std::mt19937_64 rng(14);
  const KinematicModel m = Perturbed(ReinovoLikeModel(), rng, 0.01, 0.05);
  const JointVector q = RandomJoints(m, rng);
  const auto J = ManipulatorJacobian(m, q);
  const auto Jid = IdentificationJacobian(m, q);
  for (int i = 0; i < 6; ++i) {
    EXPECT_LT((J.col(i) - Jid.col(ParameterIndex(i + 1, DhParameter::kTheta))).norm(), 1e-14);
  }
}

TEST(JacobianSingularValues, VanishAtTheWristSingularity) {
  // The classic wrist singularity: axes 4 and 6 (z3 and z5) parallel. Of the multiples of
  // 90 deg for q5, find the one where that happens (geometry, not the code under test) and
  // check the smallest singular value vanishes there and not away from it.
  const KinematicModel m = ReinovoLikeModel();
  JointVector q(6);
  q << 0.3, -0.4, 0.5, 0.2, 0.0, 0.1;
  double singular_q5 = 0.0, best_cross = 1.0;
  for (int k = -1; k <= 1; ++k) {
    q(4) = k * kPi / 2.0;
    const FrameSet f = ForwardKinematics(m, q);
    const double c = f.X_BL[3].linear().col(2).cross(f.X_BL[5].linear().col(2)).norm();
    if (c < best_cross) best_cross = c, singular_q5 = q(4);
  }
  ASSERT_LT(best_cross, 1e-12) << "no wrist singularity at a multiple of 90 deg";
  q(4) = singular_q5;
  const auto sv = JacobianSingularValues(m, q);
  EXPECT_LT(sv(6 - 1), 1e-12);  // exactly rank deficient up to rounding
  EXPECT_GE(sv(0), sv(6 - 1));
  q(4) = singular_q5 + 0.5;
  EXPECT_GT(JacobianSingularValues(m, q)(6 - 1), 1e-3);  // regular again
}

}  // namespace
}  // namespace twin
