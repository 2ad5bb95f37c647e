// The laser-tracker calibration procedure, through the Cell only, as on hardware: move the
// robot carrying the reflector to N seeded random configurations inside its joint limits
// (less a margin), skip those the cell refuses (a collision, not settled) or where the tracker
// cannot see the reflector (out of range, occluded), read the encoders and the tracker at each,
// then identify the geometry with the tracker pose and the reflector offset and score on
// held-out points (calib/procedures/tracker_calibration.h). The estimator is told the nominal
// model with the reflector offset as drawn (its tool link); nothing else.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "calib/cell/cell.h"
#include "calib/procedures/tracker_calibration.h"

namespace twin {

struct TrackerProcedureOptions {
  int poses = 100;                  ///< measured poses wanted (>= 1)
  int max_attempts = 0;             ///< configurations tried at most (0: 3 x poses)
  double joint_margin_rad = 0.1745329251994330;  ///< 10 deg off each joint limit
  std::uint64_t seed = 1;           ///< of the configurations (the estimator's randomness)
  TrackerCalibrationOptions calibration;
};

/// One configuration that gave no point, and why.
struct TrackerSkip {
  int attempt = 0;
  std::string reason;
};

struct TrackerProcedureResult {
  std::vector<TrackerPoint> points;   ///< the readings (row: attempt number)
  std::vector<TrackerSkip> skipped;
  int attempts = 0;
  /// The robot's temperature sensor at the first point [deg C], the reference of every
  /// point's context.temperature_delta_K; NaN when the cell has no sensor on the robot (the
  /// points then carry no temperature).
  double temperature_reference_C = std::numeric_limits<double>::quiet_NaN();
  TrackerCalibrationResult calibration;
};

/// The tool link of `flange_model` replaced by a reflector at p_F in the flange frame (the
/// tool link's theta, d, a place it: a = |(x, y)|, theta = atan2(y, x), d = z).
KinematicModel WithReflector(KinematicModel flange_model, const Vector3& p_F);

/// Runs the procedure on `robot` of `cell`. Throws PreconditionError for bad options (bounded
/// where the scenario is read), InputError when the cell has no tracker or fewer poses than
/// the identification needs could be measured (with the skip reasons' counts).
/// Each point's context carries the joint readings, the tracker's time stamp, the robot's
/// temperature change since the first point when the cell reads one (Cell::ReadTemperatureC:
/// a sensor reading, not a told value), and each joint's approach direction (the sign of the
/// commanded motion that reached the pose, from the readings before the move: what the
/// controller knows).
TrackerProcedureResult RunTrackerProcedure(Cell& cell, int robot, const KinematicModel& nominal,
                                           const TrackerProcedureOptions& options);
/// The same, identifying `start`: the nominal chain plus the error terms the engineer declares.
TrackerProcedureResult RunTrackerProcedure(Cell& cell, int robot, const RobotModel& start,
                                           const TrackerProcedureOptions& options);

}  // namespace twin
