#include "calib/kinematics/inverse_kinematics.h"

#include <random>
#include <string>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "test_models.h"

namespace twin {
namespace {

using testing::RandomJoints;
using testing::ReinovoLikeModel;

double RotationError(const Matrix3& a, const Matrix3& b) {
  return Eigen::AngleAxisd(a * b.transpose()).angle();
}

bool Contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

TEST(SolveIk, RoundTripsASevenJointArm) {
  // A redundant arm: any of the solutions will do; the pose is checked by FK.
  const KinematicModel m = testing::SevenJointModel();
  std::mt19937_64 rng(22);
  int successes = 0;
  constexpr int kTrials = 50;
  for (int trial = 0; trial < kTrials; ++trial) {
    const JointVector q_true = RandomJoints(m, rng);
    const Transform target = EndPose(m, q_true);
    const IkResult r = SolveIk(m, target, MidRange(m));
    if (r.status != IkStatus::kSuccess) continue;
    ++successes;
    ASSERT_EQ(r.q.size(), 7);
    EXPECT_TRUE(WithinLimits(m, r.q));
    // The defaults of IkOptions (1e-7 m, 1e-7 rad) plus rounding.
    EXPECT_LT((EndPose(m, r.q).translation() - target.translation()).norm(), 1.1e-7);
    EXPECT_LT(RotationError(EndPose(m, r.q).linear(), target.linear()), 1.1e-7);
  }
  // 48 of 50: random configurations near the limits or a singularity may defeat the restarts
  // (the six-axis test below allows the same kind of honest failure reasons).
  EXPECT_GE(successes, 48);
}

TEST(SolveIk, RoundTripsRandomReachablePoses) {
  const KinematicModel m = ReinovoLikeModel();
  std::mt19937_64 rng(21);
  int successes = 0, total_starts = 0;
  constexpr int kTrials = 200;
  for (int trial = 0; trial < kTrials; ++trial) {
    const JointVector q_true = RandomJoints(m, rng);
    const Transform target = EndPose(m, q_true);
    const JointVector seed = RandomJoints(m, rng);  // far from the answer on purpose
    const IkResult r = SolveIk(m, target, seed);
    total_starts += r.starts;
    if (r.status != IkStatus::kSuccess) {
      ADD_FAILURE() << "trial " << trial << ": " << ToString(r.status) << ": " << r.reason;
      continue;
    }
    ++successes;
    const Transform X = EndPose(m, r.q);
    // The result is checked by FK, not by the solver's own error figures. Tolerances are the
    // defaults of IkOptions (1e-7 m, 1e-7 rad) plus rounding.
    EXPECT_LT((X.translation() - target.translation()).norm(), 1.1e-7);
    EXPECT_LT(RotationError(X.linear(), target.linear()), 1.1e-7);
    EXPECT_TRUE(WithinLimits(m, r.q));
  }
  std::printf("IK round trip: %d/%d solved, %.2f starts per solve on average\n", successes,
              kTrials, static_cast<double>(total_starts) / kTrials);
}

TEST(SolveIk, NearbySeedConvergesFromTheFirstStart) {
  const KinematicModel m = ReinovoLikeModel();
  std::mt19937_64 rng(22);
  for (int trial = 0; trial < 50; ++trial) {
    const JointVector q_true = RandomJoints(m, rng);
    JointVector seed = q_true + 0.05 * JointVector::Ones(6);
    for (int i = 0; i < 6; ++i) {  // keep the seed inside the limits
      seed(i) = std::min(seed(i), m.links[i].limits.upper);
    }
    const IkResult r = SolveIk(m, EndPose(m, q_true), seed);
    ASSERT_EQ(r.status, IkStatus::kSuccess) << r.reason;
    EXPECT_EQ(r.starts, 1);
  }
}

TEST(SolveIk, PositionOnlyIgnoresOrientation) {
  const KinematicModel m = ReinovoLikeModel();
  std::mt19937_64 rng(23);
  const JointVector q_true = RandomJoints(m, rng);
  Transform target = EndPose(m, q_true);
  target.linear() = Matrix3::Identity();  // an orientation the arm may not reach there
  IkOptions o;
  o.position_only = true;
  const IkResult r = SolveIk(m, target, MidRange(m), o);
  ASSERT_EQ(r.status, IkStatus::kSuccess) << r.reason;
  EXPECT_LT((EndPose(m, r.q).translation() - target.translation()).norm(), 1.1e-7);
}

TEST(SolveIk, OutOfReachTargetFailsWithAReason) {
  const KinematicModel m = ReinovoLikeModel();
  Transform target = Transform::Identity();
  target.translation() = Vector3(2.0, 0.0, 0.5);  // the arm reaches under 1 m
  IkOptions o;
  o.random_restarts = 2;
  const IkResult r = SolveIk(m, target, MidRange(m), o);
  EXPECT_EQ(r.status, IkStatus::kNotConverged);
  EXPECT_TRUE(Contains(r.reason, "out of reach")) << r.reason;
  EXPECT_GT(r.position_error, 0.5);  // at least 2.0 - reach away
}

TEST(SolveIk, TargetOutsideJointLimitsNamesTheJoint) {
  KinematicModel m = ReinovoLikeModel();
  JointVector q_true(6);
  q_true << 1.5, 0.2, 0.3, 0.1, 0.6, 0.2;
  const Transform target = EndPose(m, q_true);
  m.links[0].limits = {-0.2, 0.2};  // joint 1 can no longer turn to 1.5 rad
  JointVector seed = q_true;
  seed(0) = 0.0;
  const IkResult r = SolveIk(m, target, seed);
  EXPECT_EQ(r.status, IkStatus::kJointLimits) << r.reason;
  EXPECT_TRUE(Contains(r.reason, "joint 1 at")) << r.reason;
}

TEST(SolveIk, InvalidInputsAreReportedNotSolved) {
  const KinematicModel m = ReinovoLikeModel();
  Transform bad = EndPose(m, MidRange(m));
  bad.translation().x() = std::nan("");
  IkResult r = SolveIk(m, bad, MidRange(m));
  EXPECT_EQ(r.status, IkStatus::kInvalidInput);
  EXPECT_TRUE(Contains(r.reason, "non-finite")) << r.reason;

  JointVector seed = MidRange(m);
  seed(2) = 10.0;
  r = SolveIk(m, EndPose(m, MidRange(m)), seed);
  EXPECT_EQ(r.status, IkStatus::kInvalidInput);
  EXPECT_TRUE(Contains(r.reason, "seed is outside the joint limits")) << r.reason;
}

// No user sets IkOptions (the CLI's `ik` sets only position_only): a bad one is our bug.
TEST(IkOptions, ValidationIsAPreconditionNamingTheField) {
  IkOptions o;
  o.damping = -1.0;
  try {
    ValidateIkOptions(o);
    FAIL() << "expected PreconditionError";
  } catch (const PreconditionError& e) {
    EXPECT_TRUE(Contains(e.what(), "IkOptions.damping")) << e.what();
  }
  o = IkOptions();
  o.max_iterations = 0;
  EXPECT_THROW(ValidateIkOptions(o), PreconditionError);
}

}  // namespace
}  // namespace twin
