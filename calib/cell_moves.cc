#include "calib/cell_moves.h"

namespace twin {

MoveResult MoveAvoidingSweep(Cell& cell, int robot, const JointVector& target) {
  MoveResult m = cell.MoveTo(robot, target);
  for (const bool wrist_first : {true, false}) {
    if (m.status != MoveStatus::kCollision) break;
    JointVector via = cell.ReadEncoders(robot);
    for (int i = 0; i < kNumJoints; ++i) {
      if ((i >= 3) == wrist_first) via(i) = target(i);
    }
    m = cell.MoveTo(robot, via);
    if (m.status == MoveStatus::kSettled) m = cell.MoveTo(robot, target);
  }
  return m;
}

}  // namespace twin
