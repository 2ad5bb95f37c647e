// The simulated operator's handclasp of TwinCell (sim/cell/twin_cell.h): JogTipToContact brings the
// jogged robot's true tip onto the other true tip, with and without alignment error, and fails
// cleanly when it cannot.
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "calib/procedures/handclasp_procedure.h"
#include "sim/world/mujoco_handles.h"
#include "sim/cell/twin_cell.h"
#include "tests/sim/test_twin_specs.h"

namespace twin {
namespace {

using testing::DemoTwinSpec;
using testing::Pose;

class HandclaspTwinTest : public ::testing::Test {
 protected:
  void SetUp() override { InstallMujocoErrorHandlers(); }
};

// The demo cell (flanges 0.45 m apart, facing each other) with 150 mm tips along the flange
// axes: the tip points start about 0.15 m apart, a short handclasp.
TwinSpec TipSpec150() {
  TwinSpec spec = DemoTwinSpec(Installation::kFloor);
  for (TipSpec& tip : spec.tips) {
    tip.X_FTip = Pose(Vector3(0, 0, 0.15));
    tip.length_m = 0.12;
  }
  return spec;
}

TEST_F(HandclaspTwinTest, JogBringsTheTrueTipsTogether) {
  TwinCell cell(TipSpec150());
  const TwinTruth before = cell.Truth();
  const double start_gap = (before.p_WTip[0] - before.p_WTip[1]).norm();
  ASSERT_GT(start_gap, 0.05);
  const MoveResult r = cell.JogTipToContact(1);
  ASSERT_EQ(r.status, MoveStatus::kSettled) << r.reason;
  const TwinTruth after = cell.Truth();
  const double gap = (after.p_WTip[0] - after.p_WTip[1]).norm();
  std::printf("[ measured ] contact gap without operator error: %.3g m (settle %.3g m)\n", gap,
              cell.last_contact_gap_m());
  EXPECT_LE(gap, TwinCell::kContactToleranceM);
  // Robot 0 held still: its tip moved by no more than the settling of a held servo.
  EXPECT_LT((after.p_WTip[0] - before.p_WTip[0]).norm(), 1e-7);
  EXPECT_GT(r.duration_s, 0.0);
}

TEST_F(HandclaspTwinTest, AlignmentErrorIsDrawnFromTheSeedAndReproducible) {
  // sigma 1 mm per axis: the gap is |N(0, sigma^2 I_3)|, below 5 sigma with probability
  // 1 - 1e-4, and two cells with the same seed draw the same error.
  double gaps[2];
  for (double& gap : gaps) {
    TwinCell cell(TipSpec150());
    cell.SetOperatorAlignmentError(1e-3);
    const MoveResult r = cell.JogTipToContact(1);
    ASSERT_EQ(r.status, MoveStatus::kSettled) << r.reason;
    const TwinTruth t = cell.Truth();
    gap = (t.p_WTip[0] - t.p_WTip[1]).norm();
  }
  std::printf("[ measured ] gap with 1 mm alignment sigma: %.3f mm\n", 1e3 * gaps[0]);
  EXPECT_GT(gaps[0], 1e-6);  // an error was applied (P(|e| < 1e-3 sigma) ~ 1e-10)
  EXPECT_LT(gaps[0], 5e-3);
  EXPECT_NEAR(gaps[0], gaps[1], 1e-9);  // same seed, same draw; settling floor 1e-9 m
}

TEST_F(HandclaspTwinTest, RejectsBadIndexAndBadSigma) {
  TwinCell cell(TipSpec150());
  EXPECT_EQ(cell.JogTipToContact(2).status, MoveStatus::kInvalidInput);
  EXPECT_EQ(cell.JogTipToContact(-1).status, MoveStatus::kInvalidInput);
  EXPECT_THROW(cell.SetOperatorAlignmentError(-1e-3), InputError);
  EXPECT_THROW(cell.SetOperatorAlignmentError(std::nan("")), InputError);
}

TEST_F(HandclaspTwinTest, OutOfReachFailsCleanlyAndMovesNothing) {
  TwinSpec spec = TipSpec150();
  spec.robots[1].X_WB = Pose(Vector3(4.0, 0, 0), Vector3::UnitZ(), kPi);  // 4 m away
  TwinCell cell(spec);
  const TwinTruth before = cell.Truth();
  const MoveResult r = cell.JogTipToContact(1);
  EXPECT_EQ(r.status, MoveStatus::kOutOfLimits);
  EXPECT_NE(r.reason.find("out of reach"), std::string::npos) << r.reason;
  EXPECT_NE(r.reason.find("nothing moved"), std::string::npos) << r.reason;
  const TwinTruth after = cell.Truth();
  EXPECT_EQ((after.q_motor[1] - before.q_motor[1]).norm(), 0.0);  // not a single command
}

}  // namespace
}  // namespace twin
