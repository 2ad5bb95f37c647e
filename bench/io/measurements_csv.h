// measurements.csv: one row per aligned pose of the optical-axis procedure (Zhu et al. 2019),
// as `twinbench run` writes it and `twinbench identify` reads it back; also the format
// `synthesize-measurements` writes. The writer and the reader of the format live here together
// (a round-trip test holds them to each other). Columns, units in the names:
//   robot, camera_robot          the passive robot whose joints are recorded; the camera's robot
//   axis, index                  optical axis k (0-based) and the pose's place along it
//   set                          calibration | validation | unused
//   q1_deg .. qN_deg             the recorded joint angles (empty past a robot's own joints)
//   du_px, dv_px                 the feature point's pixel offset from the principal point when
//                                the servo stopped
//   depth_mm                     the feature point's distance from the camera along the axis
//                                (empty: not measured)
//   offset_x_mm .. offset_z_mm   the residual offset from the axis, in the robot's base
//   frames, moves                images and moves the servo used
//   du0_px, dv0_px, pose_rms_px  the first pixel offset and the board pose's reprojection RMS
//   time_s, temperature_delta_K  the cell's clock and temperature sensor (empty: none)
// Only robot, axis, index, set and the joint columns are required; the others are read when
// present.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "calib/common/frames.h"
#include "calib/kinematics/kinematic_model.h"

namespace twin {

/// Limits of a measurements file (plausibility, issue 14): a hardware session records 50 to a
/// few hundred aligned poses, a Monte Carlo or accumulated data set tens of thousands; 100,000
/// rows, 1,000 axes and 64 MiB keep the identification's memory and time bounded (linear in
/// the rows, measured: README.md of e5af83d, "Speed"; its dense Jacobian has a column per unknown,
/// so it grows with rows times axes), 4096 characters a line.
constexpr int kMaxMeasurementRows = 100000;
constexpr int kMaxMeasurementAxes = 1000;
constexpr std::uintmax_t kMaxMeasurementBytes = std::uintmax_t{64} << 20;
constexpr std::size_t kMaxMeasurementLine = 4096;

/// One row of measurements.csv (SI inside: rad, m, s; the file holds deg and mm).
struct MeasurementRow {
  static constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  std::string robot;         ///< the robot whose joints are recorded
  std::string camera_robot;  ///< the robot that carries the camera (empty: not recorded)
  int axis = 0;              ///< optical axis index k (0-based)
  int index = 0;             ///< the pose's place along its axis
  std::string set;           ///< "calibration", "validation" or "unused"
  JointVector q;             ///< recorded joint angles [rad]
  double du_px = kNone, dv_px = kNone;    ///< pixel offset when the servo stopped [px]
  double depth_m = kNone;                 ///< distance along the axis [m]; NaN: not measured
  Vector3 offset = Vector3::Zero();       ///< residual offset from the axis, base frame [m]
  int frames = -1, moves = -1;            ///< servo images and moves; -1: not recorded
  double du0_px = kNone, dv0_px = kNone;  ///< first pixel offset [px]
  double pose_rms_px = kNone;             ///< board pose reprojection RMS [px]
  double time_s = kNone;                  ///< cell clock [s]; NaN: none
  double temperature_delta_K = kNone;     ///< temperature change [K]; NaN: none
};

/// The header line (no newline) for robots of up to `joints` joints.
std::string MeasurementsCsvHeader(int joints);

/// One data line (no newline) with `joints` joint columns; a robot with fewer joints leaves the
/// last ones empty, and NaN figures are empty fields.
std::string MeasurementsCsvRow(const MeasurementRow& row, int joints);

/// What ReadMeasurementsCsv found.
struct MeasurementsFile {
  std::string robot;               ///< the robot whose rows were read
  std::vector<MeasurementRow> rows;  ///< its rows, in file order
  std::vector<int> lines;          ///< each row's line number (1-based), for messages
  bool has_depth = false;          ///< a depth_mm column
  bool has_offset = false;         ///< offset_x_mm, offset_y_mm and offset_z_mm columns
};

/// Reads the rows of `robot` (empty: the first row's robot) from a measurements file for a
/// robot of `joints` joints. Throws InputError naming the file, line and column for: a file that
/// is not a regular file or is over kMaxMeasurementBytes, a missing required column, a
/// duplicated column, a line over kMaxMeasurementLine characters, more than kMaxMeasurementRows
/// rows, a field count that differs from the header, an unsafe robot name, a non-numeric or
/// non-finite cell, an axis index of kMaxMeasurementAxes or more, a joint angle beyond two turns,
/// a depth outside (0, 10] m, an offset of 1 m or more, a set other than the three, an axis in
/// both the calibration and the validation set, or no rows of the robot.
MeasurementsFile ReadMeasurementsCsv(const std::string& path, int joints,
                                     const std::string& robot = "");

}  // namespace twin
