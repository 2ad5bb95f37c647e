// Laser-tracker measurement files: one row per measured pose, the joint readings of the robot
// and the reflector's position in the tracker's own frame (docs/reference/file-formats.md, "Tracker
// files"). The header names the columns, with units in the names:
//   pose                         optional pose id (kept for messages)
//   q_<joint>_rad | q_<joint>_deg   one per joint of the model, <joint> the model's link name
//                                (q_S_rad) or its 1-based number (q3_deg)
//   x_m, y_m, z_m | x_mm, y_mm, z_mm   the reflector in the tracker frame
//   sigma_m | sigma_mm           optional: the tracker's stated uncertainty per axis
//   time_s                       optional: time stamp (thermal drift terms)
//   temperature_delta_K          optional: temperature change from the nominal model's state
// Any other column is refused unless named in `ignore` (e.g. a torso axis that the model
// merges into its base); the ignored columns' ranges are reported.
#pragma once

#include <string>
#include <vector>

#include "calib/kinematics/kinematic_model.h"
#include "calib/measurements/tracker_set.h"

namespace twin {

/// Limits of a tracker file (plausibility): a session measures tens to thousands of poses.
constexpr int kMaxTrackerRows = 100000;

struct TrackerFileColumn {
  std::string name;
  double min = 0, max = 0;  ///< range of an ignored column's values
};

struct TrackerFile {
  std::string path;
  std::vector<TrackerPoint> points;      ///< row = the file's line number
  std::vector<std::string> pose_ids;     ///< the pose column's text per point (empty without)
  std::vector<std::string> joint_columns;  ///< the columns read as joints, in joint order
  std::vector<TrackerFileColumn> ignored;  ///< columns dropped by request, with their ranges
  bool has_sigma = false, has_time = false, has_temperature = false;
  /// Per point, the index of its pose (PoseGroups: repeats of one pose share it).
  std::vector<int> pose_group;
  int distinct_poses = 0;  ///< number of different poses (<= points.size())
};

/// True when the file's first line names tracker columns (x_m or x_mm), i.e. when `twinbench
/// identify` should read it as a tracker file rather than as optical-axis measurements.
bool IsTrackerFile(const std::string& path);

/// Reads a tracker file for `model`. Throws InputError naming the file, line and column for a
/// missing, unknown or duplicated column, a joint column the model lacks (or a model joint the
/// file lacks), a field count that differs from the header, a non-numeric, NaN or infinite
/// cell, an implausible value (a reflector beyond 100 m, a sigma outside (0, 10 mm], a joint
/// reading beyond two turns), more than kMaxTrackerRows rows, or no rows; and, with the reason,
/// for a file that contradicts itself: a row's sigma over 100 times off the file's median, a
/// position unit whose spread is 10 times off the nominal model's motion (metres labelled mm),
/// an ignored joint column that is not constant (over 2e-3 rad).
TrackerFile ReadTrackerFile(const std::string& path, const KinematicModel& model,
                            const std::vector<std::string>& ignore = {});

}  // namespace twin
