#include "calib/cell/cell_moves.h"

namespace twin {

MoveResult MoveAvoidingSweep(Cell& cell, int robot, const JointVector& target) {
  const JointVector start = cell.ReadEncoders(robot);
  const MoveResult direct = cell.MoveTo(robot, target);
  if (direct.status != MoveStatus::kCollision) return direct;
  for (const bool wrist_first : {true, false}) {
    // Back out to the start (free: the way there was free up to the contact), then the split
    // move from there.
    if (cell.MoveTo(robot, start).status != MoveStatus::kSettled) return direct;
    JointVector via = start;
    const int wrist = static_cast<int>(start.size()) - 3;  // the last three joints
    for (int i = 0; i < start.size(); ++i) {
      if ((i >= wrist) == wrist_first) via(i) = target(i);
    }
    if (cell.MoveTo(robot, via).status == MoveStatus::kSettled) {
      const MoveResult last = cell.MoveTo(robot, target);
      if (last.status == MoveStatus::kSettled) return last;
    }
  }
  cell.MoveTo(robot, start);  // leave the robot where it was
  return direct;
}

}  // namespace twin
