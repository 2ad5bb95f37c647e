#include "calib/cell/cell_moves.h"

#include <vector>

#include <gtest/gtest.h>

namespace twin {
namespace {

// A cell whose straight joint-space moves collide when they change an arm joint (1-3) and a
// wrist joint (4-6) at once (a wrist swinging the tool through the upper arm), or whenever the
// target is in `blocked_targets`; a colliding move leaves the robot where it was.
class SweepCell : public Cell {
 public:
  MoveResult MoveTo(int robot, const JointVector& q) override {
    calls.push_back(q);
    MoveResult r;
    const JointVector d = q - q_[robot];
    const bool arm = d.head<3>().cwiseAbs().maxCoeff() > 1e-12;
    const bool wrist = d.tail<3>().cwiseAbs().maxCoeff() > 1e-12;
    if ((arm && wrist) || target_blocked) {
      r.status = MoveStatus::kCollision;
      r.reason = "fake sweep";
      return r;
    }
    q_[robot] = q;
    return r;
  }
  JointVector ReadEncoders(int robot) override { return q_[robot]; }
  cv::Mat GrabImage() override { return {}; }
  MoveResult ExchangeTools() override { return {}; }
  int CameraRobot() override { return 0; }
  std::vector<JointVector> calls;
  bool target_blocked = false;

 private:
  JointVector q_[2] = {JointVector::Zero(6), JointVector::Zero(6)};
};

TEST(CellMoves, ASweptPathIsSplitIntoWristAndArmMoves) {
  SweepCell cell;
  const JointVector target = (JointVector(6) << 0.1, 0.2, 0.3, 0.4, 0.5, 0.6).finished();
  const MoveResult m = MoveAvoidingSweep(cell, 1, target);
  EXPECT_EQ(m.status, MoveStatus::kSettled) << m.reason;
  EXPECT_EQ(cell.ReadEncoders(1), target);
  // direct (collides), back to the start, wrist only, then the arm
  ASSERT_EQ(cell.calls.size(), 4u);
  EXPECT_EQ(cell.calls[1], JointVector::Zero(6));
  EXPECT_EQ(cell.calls[2].head<3>(), JointVector::Zero(6).head<3>());
  EXPECT_EQ(cell.calls[2].tail<3>(), target.tail<3>());
}

TEST(CellMoves, AFreeMoveIsOneMoveAndABlockedTargetStaysAFailure) {
  SweepCell cell;
  JointVector wrist_only = JointVector::Zero(6);
  wrist_only(4) = 0.3;
  EXPECT_EQ(MoveAvoidingSweep(cell, 0, wrist_only).status, MoveStatus::kSettled);
  EXPECT_EQ(cell.calls.size(), 1u);
  cell.target_blocked = true;
  const MoveResult m = MoveAvoidingSweep(cell, 0, JointVector::Constant(6, 0.2));
  EXPECT_EQ(m.status, MoveStatus::kCollision);
  EXPECT_EQ(cell.ReadEncoders(0), wrist_only);  // stayed where it was
}

}  // namespace
}  // namespace twin
