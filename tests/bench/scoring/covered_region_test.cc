// The covered-region truth score (bench/scoring/calibration_scoring.h).
#include <gtest/gtest.h>

#include "bench/io/model_loader.h"
#include "bench/scoring/calibration_scoring.h"
#include "calib/model/parameters.h"

namespace twin {
namespace {

const std::string kRoot = TWIN_SOURCE_DIR;

TEST(CoveredRegion, TheBoxIsThePosesRangePerJoint) {
  JointVector a(3), b(3), c(3);
  a << 0.1, -0.2, 0.3;
  b << -0.4, 0.5, 0.3;
  c << 0.0, 0.0, 0.9;
  const JointBox box = CoveredJointBox({a, b, c});
  EXPECT_DOUBLE_EQ(box.lower(0), -0.4);
  EXPECT_DOUBLE_EQ(box.upper(0), 0.1);
  EXPECT_DOUBLE_EQ(box.lower(1), -0.2);
  EXPECT_DOUBLE_EQ(box.upper(1), 0.5);
  EXPECT_DOUBLE_EQ(box.lower(2), 0.3);
  EXPECT_DOUBLE_EQ(box.upper(2), 0.9);
  for (const JointVector& q : RandomJointConfigurationsIn(box, 50, 7)) {
    for (int i = 0; i < 3; ++i) {
      EXPECT_GE(q(i), box.lower(i));
      EXPECT_LE(q(i), box.upper(i));
    }
  }
  EXPECT_THROW(CoveredJointBox({}), std::logic_error);
}

// A joint-1 offset error turns the whole arm about the base axis: a rigid motion, which the
// rigid gauge must absorb exactly; a link-length error is not one and must stay.
TEST(CoveredRegion, ARigidMotionOfTheWholeArmIsAbsorbedByTheRigidGauge) {
  const KinematicModel nominal = LoadRobotModel(kRoot + "/models/reinovo_r1.yaml", {});
  KinematicModel truth = nominal;
  truth.links[0].dh.theta_offset += 0.01;  // the whole arm turned about the joint-1 axis
  KinematicModel wrong = nominal;
  wrong.links[2].dh.a += 0.002;  // a 2 mm link-length error
  JointVector lo(6), hi(6);
  lo << -0.5, -0.3, -0.3, -0.5, 0.5, -0.5;
  hi << 0.5, 0.3, 0.3, 0.5, 1.0, 0.5;
  const RegionScore s = ScoreRegion(nominal, wrong, truth, JointBox{lo, hi}, 100, 3);
  EXPECT_EQ(s.configurations, 100);
  // nominal vs truth differ by a rigid motion: raw error of millimetres, rigid gauge ~0
  // (1e-9 m: the Umeyama fit's round-off on 100 points).
  EXPECT_GT(s.before.raw.rms, 1e-3);
  EXPECT_LT(s.before.rigid.rms, 1e-9);
  // the 2 mm length error is not a rigid motion: it stays, below its own size.
  EXPECT_GT(s.after.rigid.rms, 1e-5);
  EXPECT_LT(s.after.rigid.rms, 2e-3);
}

}  // namespace
}  // namespace twin
