#include "calib/kinematics/spherical_wrist_ik.h"

#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "calib/kinematics/forward_kinematics.h"
#include "test_models.h"

namespace twin {
namespace {

using testing::RandomJoints;
using testing::RandomTransform;
using testing::ReinovoLikeModel;

double RotationError(const Matrix3& a, const Matrix3& b) {
  return Eigen::AngleAxisd(a * b.transpose()).angle();
}

// Largest joint difference, each taken modulo a whole turn [rad].
double TurnDistance(const JointVector& a, const JointVector& b) {
  double d = 0.0;
  for (int i = 0; i < a.size(); ++i) {
    d = std::max(d, std::abs(std::remainder(a(i) - b(i), 2.0 * kPi)));
  }
  return d;
}

double NearestSolution(const std::vector<JointVector>& solutions, const JointVector& q) {
  double best = INFINITY;
  for (const JointVector& s : solutions) best = std::min(best, TurnDistance(s, q));
  return best;
}

bool Contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// The Reinovo arm with a base and an end transform that are not the identity: the closed form
// reads the axes from the model's forward kinematics, so they must not matter.
KinematicModel MountedReinovo(int robot, std::mt19937_64& rng) {
  KinematicModel m = ReinovoLikeModel(robot);
  m.X_BL0 = RandomTransform(rng, 0.3);
  m.X_LtE = RandomTransform(rng, 0.15);
  return m;
}

TEST(SphericalWristIk, EverySolutionReachesTheTargetAndOneIsTheJointsItCameFrom) {
  std::mt19937_64 rng(42);
  for (int robot = 0; robot < 2; ++robot) {
    for (const KinematicModel& m : {ReinovoLikeModel(robot), MountedReinovo(robot, rng)}) {
      std::string why;
      const auto ik = SphericalWristIk::For(m, &why);
      ASSERT_TRUE(ik.has_value()) << why;
      for (int trial = 0; trial < 300; ++trial) {
        const JointVector q = RandomJoints(m, rng);
        const Transform target = EndPose(m, q);
        const std::vector<JointVector> solutions = ik->Solve(target);
        // At least the joints the target came from and their wrist flipped (joint 4 half a turn
        // on, joint 5 mirrored, joint 6 half a turn on), which ends in the same pose.
        ASSERT_GE(solutions.size(), 2u) << "trial " << trial;
        for (size_t i = 0; i < solutions.size(); ++i) {
          // Forward kinematics of each answer, computed here: double rounding over a 1 m chain
          // is ~1e-15 m; 1e-9 leaves room for the acos of near-stretched elbows.
          const Transform X = EndPose(m, solutions[i]);
          EXPECT_LT((X.translation() - target.translation()).norm(), 1e-9);
          EXPECT_LT(RotationError(X.linear(), target.linear()), 1e-9);
          for (size_t j = 0; j < i; ++j) {  // each answer once
            EXPECT_GT(TurnDistance(solutions[i], solutions[j]), 1e-6) << "trial " << trial;
          }
        }
        // The joints the target came from are among the answers. 1e-6 rad: an acos near +-1
        // (elbow or wrist near straight) keeps only about half the digits of its argument.
        EXPECT_LT(NearestSolution(solutions, q), 1e-6) << "trial " << trial;
      }
    }
  }
}

TEST(SphericalWristIk, AgreesWithTheIterativeSolver) {
  const KinematicModel m = ReinovoLikeModel(1);
  const auto ik = SphericalWristIk::For(m, nullptr);
  ASSERT_TRUE(ik.has_value());
  std::mt19937_64 rng(7);
  int compared = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Transform target = EndPose(m, RandomJoints(m, rng));
    const IkResult it = SolveIk(m, target, RandomJoints(m, rng));
    if (it.status != IkStatus::kSuccess) continue;
    // Away from singular poses only: the iterative answer is within 1e-7 m and 1e-7 rad of the
    // pose, which bounds its joint error by about 1e-7 / sigma_min; sigma_min >= 0.01 gives
    // 1e-5 rad, and 1e-4 leaves a factor of 10.
    if (SmallestJacobianSingularValue(m, it.q) < 0.01) continue;
    ++compared;
    EXPECT_LT(NearestSolution(ik->Solve(target), it.q), 1e-4) << "trial " << trial;
  }
  EXPECT_GT(compared, 150);  // the iterative solver succeeds on nearly all of them
}

// Joint 5 straight (axes 4 and 6 in line): joints 4 and 6 turn the same axis, a family of
// answers. The closed form must still give one that reaches the pose with the joints 1-3 the
// target came from (rounding noise under the square root of the wrist's subproblem made it
// lose every wrist answer there before).
TEST(SphericalWristIk, AStraightWristStillHasAnAnswer) {
  const KinematicModel m = ReinovoLikeModel();
  const auto ik = SphericalWristIk::For(m, nullptr);
  ASSERT_TRUE(ik.has_value());
  // The joint-5 angle where axes 4 and 6 line up, found here by forward kinematics.
  JointVector q = (JointVector(6) << 0.3, -0.4, 0.6, 0.7, 0.0, -0.5).finished();
  double straight = NAN;
  for (double q5 : {0.0, kPi / 2, -kPi / 2}) {
    q(4) = q5;
    const FrameSet f = ForwardKinematics(m, q);
    if (std::abs(f.X_BL[3].linear().col(2).dot(f.X_BL[5].linear().col(2))) > 1.0 - 1e-12) {
      straight = q5;
    }
  }
  ASSERT_FALSE(std::isnan(straight));
  std::mt19937_64 rng(9);
  for (int trial = 0; trial < 50; ++trial) {
    q = RandomJoints(m, rng);
    q(4) = straight;
    const Transform target = EndPose(m, q);
    const std::vector<JointVector> solutions = ik->Solve(target);
    bool same_arm = false;
    for (const JointVector& s : solutions) {
      // As in the tests above: FK here, 1e-9 for rounding.
      EXPECT_LT((EndPose(m, s).translation() - target.translation()).norm(), 1e-9);
      const double arm = std::max({std::abs(std::remainder(s(0) - q(0), 2 * kPi)),
                                   std::abs(std::remainder(s(1) - q(1), 2 * kPi)),
                                   std::abs(std::remainder(s(2) - q(2), 2 * kPi))});
      // 1e-6 rad as above; the wrist's answer is one of its family, checked by FK above.
      same_arm |= arm < 1e-6;
    }
    EXPECT_TRUE(same_arm) << "trial " << trial << ", " << solutions.size() << " answers";
  }
}

TEST(SphericalWristIk, RefusesArmsWithoutTheStructureAndSaysWhy) {
  std::string why;
  EXPECT_FALSE(SphericalWristIk::For(testing::SevenJointModel(), &why).has_value());
  EXPECT_TRUE(Contains(why, "7 joints")) << why;

  KinematicModel offset_wrist = ReinovoLikeModel();
  offset_wrist.links[4].dh.d = 0.1;  // a UR-like offset between wrist axes 5 and 6
  EXPECT_FALSE(SphericalWristIk::For(offset_wrist, &why).has_value());
  EXPECT_TRUE(Contains(why, "wrist axes do not meet")) << why;

  KinematicModel twisted = ReinovoLikeModel();
  twisted.links[1].dh.alpha = 1e-4;  // joints 2 and 3 no longer parallel
  EXPECT_FALSE(SphericalWristIk::For(twisted, &why).has_value());
  EXPECT_TRUE(Contains(why, "joints 2 and 3 are not parallel")) << why;

  // A calibrated model: every parameter a little off, as identification leaves it.
  std::mt19937_64 rng(3);
  EXPECT_FALSE(SphericalWristIk::For(testing::Perturbed(ReinovoLikeModel(), rng, 1e-3, 1e-3),
                                     &why).has_value());
}

TEST(SphericalWristIk, GivesNothingForATargetOutOfReach) {
  const KinematicModel m = ReinovoLikeModel();
  const auto ik = SphericalWristIk::For(m, nullptr);
  ASSERT_TRUE(ik.has_value());
  Transform far = Transform::Identity();
  far.translation() = Vector3(5.0, 0.0, 0.5);  // the arm reaches under 1 m
  EXPECT_TRUE(ik->Solve(far).empty());
}

TEST(SolveIkSphericalWrist, TakesTheNearestSolutionInsideTheLimitsWithoutIterating) {
  const KinematicModel m = ReinovoLikeModel();
  const auto ik = SphericalWristIk::For(m, nullptr);
  ASSERT_TRUE(ik.has_value());
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 100; ++trial) {
    const Transform target = EndPose(m, RandomJoints(m, rng));
    const JointVector seed = RandomJoints(m, rng);
    const IkResult r = SolveIkSphericalWrist(m, target, seed);
    ASSERT_EQ(r.status, IkStatus::kSuccess) << r.reason;
    EXPECT_EQ(r.iterations, 0);
    EXPECT_TRUE(WithinLimits(m, r.q));
    EXPECT_LT(r.position_error, 1e-9);
    EXPECT_LT(r.orientation_error, 1e-9);
    // No other solution inside the limits is nearer the seed (each at its nearest turns).
    for (JointVector s : ik->Solve(target)) {
      s = NearestTurns(m, s, seed);
      if (WithinLimits(m, s)) {
        EXPECT_GE((s - seed).norm(), (r.q - seed).norm() - 1e-12);
      }
    }
  }
}

// Limits wider than a turn on one side only (KUKA's A2: -190..45 deg): the answer at -185 deg
// is found as -185, not dropped as 175 (outside) nor taken at 175.
TEST(SolveIkSphericalWrist, TurnsEachJointIntoLopsidedLimits) {
  KinematicModel m = ReinovoLikeModel();
  m.links[1].limits = {DegToRad(-190.0), DegToRad(45.0)};
  JointVector q = (JointVector(6) << 0.2, DegToRad(-185.0), 0.4, 0.3, 0.8, -0.2).finished();
  ASSERT_TRUE(WithinLimits(m, q));
  const IkResult r = SolveIkSphericalWrist(m, EndPose(m, q), q);
  ASSERT_EQ(r.status, IkStatus::kSuccess) << r.reason;
  EXPECT_EQ(r.iterations, 0);  // the closed form answered, not the fallback
  EXPECT_LT((r.q - q).norm(), 1e-6);  // the seed is an answer: it is the nearest (1e-6: above)
}

TEST(SolveIkSphericalWrist, FallsBackToTheIterativeSolver) {
  // A seven-joint arm has no closed form here: the iterative solver answers.
  const KinematicModel m = testing::SevenJointModel();
  std::mt19937_64 rng(5);
  const Transform target = EndPose(m, RandomJoints(m, rng));
  const IkResult r = SolveIkSphericalWrist(m, target, MidRange(m));
  ASSERT_EQ(r.status, IkStatus::kSuccess) << r.reason;
  EXPECT_GT(r.iterations, 0);
  // IkOptions' default position tolerance, 1e-7 m, plus rounding.
  EXPECT_LT((EndPose(m, r.q).translation() - target.translation()).norm(), 1.1e-7);
  // Tolerances tighter than the closed form's 1e-9: the iterative solver answers.
  IkOptions tight;
  tight.position_tolerance = tight.orientation_tolerance = 1e-10;
  const KinematicModel reinovo = ReinovoLikeModel();
  const Transform pose = EndPose(reinovo, RandomJoints(reinovo, rng));
  EXPECT_GT(SolveIkSphericalWrist(reinovo, pose, MidRange(reinovo), tight).iterations, 0);
  // Position only: the closed form needs the orientation, so the iterative solver answers.
  IkOptions position_only;
  position_only.position_only = true;
  const KinematicModel six = ReinovoLikeModel();
  const IkResult p =
      SolveIkSphericalWrist(six, EndPose(six, RandomJoints(six, rng)), MidRange(six), position_only);
  EXPECT_EQ(p.status, IkStatus::kSuccess) << p.reason;
  EXPECT_GT(p.iterations, 0);
}

}  // namespace
}  // namespace twin
