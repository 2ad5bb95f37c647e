// Moves through the Cell that work around a blocked straight joint-space path.
#pragma once

#include "calib/cell/cell.h"

namespace twin {

/// Moves robot `robot` to `target`. A settled MoveTo is a straight line in joint space, which
/// can sweep a link through the robot's own tool or the other robot even when both ends are
/// free; when the direct move reports a collision, it backs out to the start and tries the
/// wrist joints (4-6) first and the arm (1-3) after them, then the arm first. Returns a settled
/// result when the robot reached `target`; otherwise the direct move's failure, with the robot
/// moved back to where it started.
MoveResult MoveAvoidingSweep(Cell& cell, int robot, const JointVector& target);

}  // namespace twin
