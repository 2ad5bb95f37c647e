#include "calib/identification/tip_refinement.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "calib/identification/base_calibration.h"
#include "calib/common/errors.h"

namespace twin {
namespace {

// Synthetic handclasp contacts (no kinematics: the solver takes flange poses). Robot 1's tip
// points along flange z from (-60, 60, 100) mm, robot 2's radially along flange -x from
// (-150, 0, 20) mm, as in scenarios/workflow_dual.yaml; the true tips differ from the nominal
// ones by dt1, dt2. At each contact robot 2's tip faces robot 1's (z_tip2 = -z_tip1), as the
// operator brings them together.
struct Contacts {
  std::vector<Transform> X_B1F1, X_B2F2;
  Vector3 z1_world_last;
};

const Vector3 kT1(-0.06, 0.06, 0.10), kT2(-0.15, 0.0, 0.02);
const Vector3 kAxis1(0, 0, 1), kAxis2(-1, 0, 0);

Transform TrueX() {
  Transform X = Transform::Identity();
  X.linear() = RotationFromZyz(Vector3(DegToRad(179.7), DegToRad(0.2), DegToRad(-0.1)));
  X.translation() = Vector3(1.2032, -0.0026, 0.0008);
  return X;
}

Matrix3 RotationTaking(const Vector3& from, const Vector3& to) {
  return Eigen::Quaterniond::FromTwoVectors(from, to).toRotationMatrix();
}

// `tilt_deg`: spread of robot 1's tip direction about the direction to robot 2; 0 gives the
// same orientation at every contact.
Contacts MakeContacts(int n, double tilt_deg, const Vector3& dt1, const Vector3& dt2,
                      double noise_m, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  const Transform X = TrueX();
  Contacts c;
  for (int i = 0; i < n; ++i) {
    const Vector3 p(0.45 + 0.3 * unit(rng), 0.3 * unit(rng), 0.3 + 0.15 * unit(rng));
    Vector3 dir = Vector3::UnitX();  // towards robot 2
    Matrix3 roll1 = Eigen::AngleAxisd(kPi * unit(rng), Vector3::UnitZ()).toRotationMatrix();
    if (tilt_deg > 0) {
      const Vector3 axis = Vector3(0, unit(rng), unit(rng)).normalized();
      dir = Eigen::AngleAxisd(DegToRad(tilt_deg) * unit(rng), axis) * dir;
    } else {
      roll1 = Matrix3::Identity();
    }
    const Matrix3 R1 = RotationTaking(kAxis1, dir) * roll1;
    Transform F1 = Transform::Identity();
    F1.linear() = R1;
    F1.translation() = p - R1 * (kT1 + dt1);
    Matrix3 roll2 = Eigen::AngleAxisd(tilt_deg > 0 ? kPi * unit(rng) : 0.3, -dir).toRotationMatrix();
    const Matrix3 R2 = roll2 * RotationTaking(kAxis2, -dir);
    Transform F2w = Transform::Identity();
    F2w.linear() = R2;
    Vector3 p2 = p;
    for (int k = 0; k < 3; ++k) p2(k) += noise_m * normal(rng);
    F2w.translation() = p2 - R2 * (kT2 + dt2);
    c.X_B1F1.push_back(F1);
    c.X_B2F2.push_back(X.inverse() * F2w);
  }
  return c;
}

Transform Perturbed(const Transform& X) {
  Transform Y = X;
  Y.linear() = Y.linear() * Eigen::AngleAxisd(0.01, Vector3(1, 2, 3).normalized());
  Y.translation() += Vector3(0.004, -0.003, 0.002);
  return Y;
}

TEST(TipRefinement, RecoversBaseAndTipsExactlyFromNoiseFreeContacts) {
  // dt1 perpendicular to tip 1's axis: inside the gauge, so every unknown is exact.
  const Vector3 dt1(0.0012, -0.0008, 0.0), dt2(0.0007, 0.0011, -0.0009);
  const Contacts c = MakeContacts(16, 30.0, dt1, dt2, 0.0, 1);
  const TipRefinementResult r =
      RefineBaseAndTips(c.X_B1F1, c.X_B2F2, kT1, kT2, kAxis1, Perturbed(TrueX()));
  ASSERT_TRUE(r.ok) << r.reason;
  // Round-off level: metres of 1e-9 are nanometres, far below any physical effect.
  EXPECT_LT((r.dt1_F1 - dt1).norm(), 1e-9);
  EXPECT_LT((r.dt2_F2 - dt2).norm(), 1e-9);
  EXPECT_LT((r.X_B1B2.translation() - TrueX().translation()).norm(), 1e-9);
  EXPECT_LT(Eigen::AngleAxisd(r.X_B1B2.linear().transpose() * TrueX().linear()).angle(), 1e-9);
  EXPECT_LT(r.rms_residual_m, 1e-9);
  EXPECT_GT(r.rms_residual_before_m, 1e-3);
}

TEST(TipRefinement, TipLengthsAlongTheCommonAxisAreAGaugeThatLeavesTheBaseExact) {
  // 2 mm more of tip 1 along its own axis: the same contacts as 2 mm less of tip 2 along its
  // axis (-x of flange 2), so the solver (dt1 kept perpendicular) moves it to tip 2 and X is
  // untouched.
  const Vector3 dt1(0.001, 0.0, 0.002), dt2(0.0, 0.0005, 0.0);
  const Contacts c = MakeContacts(16, 30.0, dt1, dt2, 0.0, 2);
  const TipRefinementResult r =
      RefineBaseAndTips(c.X_B1F1, c.X_B2F2, kT1, kT2, kAxis1, Perturbed(TrueX()));
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_LT((r.dt1_F1 - Vector3(0.001, 0.0, 0.0)).norm(), 1e-9);
  EXPECT_LT((r.dt2_F2 - (dt2 + 0.002 * kAxis2)).norm(), 1e-9);
  EXPECT_LT((r.X_B1B2.translation() - TrueX().translation()).norm(), 1e-9);
  EXPECT_LT(Eigen::AngleAxisd(r.X_B1B2.linear().transpose() * TrueX().linear()).angle(), 1e-9);
}

TEST(TipRefinement, NoisyContactsGiveErrorsWithinTheReportedSigma) {
  const Vector3 dt1(0.0012, -0.0008, 0.0), dt2(0.0007, 0.0011, -0.0009);
  const Contacts c = MakeContacts(24, 30.0, dt1, dt2, 1e-4, 3);
  const TipRefinementResult r =
      RefineBaseAndTips(c.X_B1F1, c.X_B2F2, kT1, kT2, kAxis1, Perturbed(TrueX()));
  ASSERT_TRUE(r.ok) << r.reason;
  // 4 sigma per component: a correct covariance fails this with probability < 1e-3 per check.
  for (int k = 0; k < 3; ++k) {
    EXPECT_LE(std::abs(r.dt2_F2(k) - dt2(k)), 4 * r.sigma_dt2_F2(k) + 1e-12) << k;
    EXPECT_LE(std::abs(r.dt1_F1(k) - dt1(k)), 4 * r.sigma_dt1_F1(k) + 1e-12) << k;
  }
  // The sigmas themselves are of the contact noise's order (0.1 mm), not inflated.
  EXPECT_LT(r.sigma_dt2_F2.maxCoeff(), 3e-4);
  // The residual is the contact noise: sqrt(3) * 0.1 mm per contact less the fitted share.
  EXPECT_LT(r.rms_residual_m, 2e-4);
  EXPECT_GT(r.rms_residual_m, 5e-5);
}

TEST(TipRefinement, RefusesContactsWithoutOrientationVariety) {
  const Contacts c = MakeContacts(12, 0.0, Vector3::Zero(), Vector3::Zero(), 0.0, 4);
  const TipRefinementResult r =
      RefineBaseAndTips(c.X_B1F1, c.X_B2F2, kT1, kT2, kAxis1, Perturbed(TrueX()));
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.reason.find("vary too little"), std::string::npos) << r.reason;
}

// The flange poses, tips and options all come from our own code (forward kinematics,
// validated models, fixed options): malformed ones are broken preconditions.
TEST(TipRefinement, RejectsBrokenPreconditions) {
  const Contacts c = MakeContacts(6, 30.0, Vector3::Zero(), Vector3::Zero(), 0.0, 5);
  std::vector<Transform> shorter(c.X_B2F2.begin(), c.X_B2F2.end() - 1);
  EXPECT_THROW(RefineBaseAndTips(c.X_B1F1, shorter, kT1, kT2, kAxis1, TrueX()),
               PreconditionError);
  EXPECT_THROW(RefineBaseAndTips(c.X_B1F1, c.X_B2F2, kT1, kT2, Vector3::Zero(), TrueX()),
               PreconditionError);
  std::vector<Transform> three(c.X_B1F1.begin(), c.X_B1F1.begin() + 3);
  std::vector<Transform> three2(c.X_B2F2.begin(), c.X_B2F2.begin() + 3);
  const TipRefinementResult r = RefineBaseAndTips(three, three2, kT1, kT2, kAxis1, TrueX());
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.reason.find("at least 4"), std::string::npos) << r.reason;
  TipRefinementOptions bad;
  bad.max_iterations = 0;
  EXPECT_THROW(RefineBaseAndTips(c.X_B1F1, c.X_B2F2, kT1, kT2, kAxis1, TrueX(), bad),
               PreconditionError);
}

}  // namespace
}  // namespace twin
