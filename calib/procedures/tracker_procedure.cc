#include "calib/procedures/tracker_procedure.h"

#include <cmath>
#include <map>
#include <random>

#include "calib/common/errors.h"
#include "calib/model/robot_model.h"

namespace twin {

KinematicModel WithReflector(KinematicModel m, const Vector3& p_F) {
  Link& tool = m.tool();
  tool.dh.theta_offset = std::atan2(p_F.y(), p_F.x());
  tool.dh.d = p_F.z();
  tool.dh.a = std::hypot(p_F.x(), p_F.y());
  tool.dh.alpha = 0.0;
  tool.dh.beta = 0.0;
  m.X_LtE = Transform::Identity();
  return m;
}

TrackerProcedureResult RunTrackerProcedure(Cell& cell, int robot, const KinematicModel& nominal,
                                           const TrackerProcedureOptions& o) {
  return RunTrackerProcedure(cell, robot, MakeRobotModel(nominal), o);
}

TrackerProcedureResult RunTrackerProcedure(Cell& cell, int robot, const RobotModel& start,
                                           const TrackerProcedureOptions& o) {
  const KinematicModel& nominal = start.chain;
  // The scenario's tracker_calibration.poses is bounded where it is read (bench/runs).
  TWIN_REQUIRE(o.poses >= 1 && o.poses <= 100000,
               "expected 1 to 100000 poses, got " + std::to_string(o.poses));
  const int attempts = o.max_attempts > 0 ? o.max_attempts : 3 * o.poses;
  TrackerProcedureResult out;
  std::mt19937_64 rng(o.seed);
  std::map<std::string, int> why;  // skip causes, for the refusal's message
  for (int a = 0; a < attempts && static_cast<int>(out.points.size()) < o.poses; ++a) {
    JointVector q = ZeroJoints(nominal);
    for (int i = 0; i < nominal.num_joints(); ++i) {
      const JointLimits& l = nominal.links[i].limits;
      const double lo = l.lower + o.joint_margin_rad, hi = l.upper - o.joint_margin_rad;
      q(i) = lo < hi ? std::uniform_real_distribution<double>(lo, hi)(rng) : 0.5 * (l.lower + l.upper);
    }
    ++out.attempts;
    const JointVector before = cell.ReadEncoders(robot);
    const MoveResult move = cell.MoveTo(robot, q);
    if (move.status != MoveStatus::kSettled) {
      out.skipped.push_back({a, std::string("move ") + ToString(move.status) + ": " + move.reason});
      ++why[std::string("move ") + ToString(move.status)];
      continue;
    }
    const JointVector reading = cell.ReadEncoders(robot);
    const TrackerReading t = cell.MeasureTracker(robot);
    if (t.status == TrackerStatus::kNoTracker) {
      throw InputError("tracker_calibration", t.reason);
    }
    if (t.status != TrackerStatus::kOk) {
      out.skipped.push_back({a, std::string(ToString(t.status)) + ": " + t.reason});
      ++why[ToString(t.status)];
      continue;
    }
    TrackerPoint p;
    p.context.q = reading;
    p.context.time_s = t.time_s;
    p.context.temperature_delta_K =
        ReadTemperatureDeltaK(cell, robot, &out.temperature_reference_C);
    p.context.approach = ApproachDirections(before, q);
    p.p_T = t.p_T;
    p.row = a + 1;
    out.points.push_back(p);
  }
  if (static_cast<int>(out.points.size()) < o.poses) {
    std::string causes;
    for (const auto& [cause, n] : why) {
      causes += (causes.empty() ? "" : ", ") + std::to_string(n) + " " + cause;
    }
    throw InputError("tracker_calibration", "measured " + std::to_string(out.points.size()) +
                                                " of " + std::to_string(o.poses) + " poses in " +
                                                std::to_string(attempts) + " attempts (" +
                                                causes + ")");
  }
  TrackerCalibrationOptions co = o.calibration;
  co.set.source = "tracker_calibration";
  out.calibration = CalibrateFromTracker(start, out.points, {}, co);
  return out;
}

}  // namespace twin
