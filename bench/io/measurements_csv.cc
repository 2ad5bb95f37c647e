#include "bench/io/measurements_csv.h"

#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "bench/io/csv.h"
#include "bench/io/output_files.h"
#include "bench/io/yaml_util.h"
#include "calib/common/errors.h"

namespace twin {
namespace {

// A figure with `precision` significant digits, or an empty field where it is NaN (no clock, no
// temperature sensor, not recorded).
std::string Field(double v, int precision) {
  if (!std::isfinite(v)) return "";
  std::ostringstream os;
  os.precision(precision);
  os << v;
  return os.str();
}

// Where a refusal points: "FILE:LINE" or "FILE:LINE column".
std::string At(const std::string& path, int line, const std::string& column = "") {
  return path + ":" + std::to_string(line) + (column.empty() ? "" : " " + column);
}

}  // namespace

std::string MeasurementsCsvHeader(int joints) {
  std::string h = "robot,camera_robot,axis,index,set";
  for (int i = 1; i <= joints; ++i) h += ",q" + std::to_string(i) + "_deg";
  return h + ",du_px,dv_px,depth_mm,offset_x_mm,offset_y_mm,offset_z_mm,frames,moves,du0_px,"
             "dv0_px,pose_rms_px,time_s,temperature_delta_K";
}

std::string MeasurementsCsvRow(const MeasurementRow& r, int joints) {
  std::ostringstream os;
  os << r.robot << ',' << r.camera_robot << ',' << r.axis << ',' << r.index << ',' << r.set;
  for (int i = 0; i < joints; ++i) {
    os << ',';
    if (i < r.q.size()) os << Field(RadToDeg(r.q(i)), 10);
  }
  os << ',' << Field(r.du_px, 6) << ',' << Field(r.dv_px, 6) << ',' << Field(1000 * r.depth_m, 10)
     << ',' << Field(1000 * r.offset.x(), 10) << ',' << Field(1000 * r.offset.y(), 10) << ','
     << Field(1000 * r.offset.z(), 10) << ',' << (r.frames >= 0 ? std::to_string(r.frames) : "")
     << ',' << (r.moves >= 0 ? std::to_string(r.moves) : "") << ',' << Field(r.du0_px, 6) << ','
     << Field(r.dv0_px, 6) << ',' << Field(r.pose_rms_px, 4) << ',' << Field(r.time_s, 10) << ','
     << Field(r.temperature_delta_K, 6);
  return os.str();
}

MeasurementsFile ReadMeasurementsCsv(const std::string& path, int joints,
                                     const std::string& robot_wanted) {
  RequireRegularFile(path, kMaxMeasurementBytes);
  NoteInput(path);
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot read the measurements file");
  std::string line;
  if (!std::getline(in, line)) throw InputError(path, "empty file");
  if (!line.empty() && line.back() == '\r') line.pop_back();  // CRLF files
  if (line.size() > kMaxMeasurementLine) {
    throw InputError(At(path, 1), "header line longer than " +
                                      std::to_string(kMaxMeasurementLine) + " characters");
  }
  const std::vector<std::string> header = SplitCsv(line);
  std::map<std::string, std::size_t> col;
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (!col.emplace(header[i], i).second) {
      throw InputError(At(path, 1), "column '" + header[i] + "' appears twice");
    }
  }
  std::vector<std::string> needed = {"robot", "axis", "index", "set"};
  for (int i = 1; i <= joints; ++i) needed.push_back("q" + std::to_string(i) + "_deg");
  for (const std::string& need : needed) {
    if (!col.count(need)) {
      throw InputError(At(path, 1), "missing column '" + need + "' (expected the header of "
                                    "`twinbench run`'s measurements.csv)");
    }
  }
  MeasurementsFile out;
  out.robot = robot_wanted;
  out.has_depth = col.count("depth_mm") != 0;
  out.has_offset = col.count("offset_x_mm") && col.count("offset_y_mm") && col.count("offset_z_mm");
  std::set<int> cal_axes, val_axes;
  int line_number = 1, rows = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.size() > kMaxMeasurementLine) {
      throw InputError(At(path, line_number), "line longer than " +
                                                  std::to_string(kMaxMeasurementLine) +
                                                  " characters");
    }
    if (!line.empty() && line.back() == '\r') line.pop_back();  // CRLF files
    if (line.empty()) continue;
    const std::string where = At(path, line_number);
    if (++rows > kMaxMeasurementRows) {
      throw InputError(where, "more than " + std::to_string(kMaxMeasurementRows) +
                                  " measurement rows (a session records 50 to a few hundred "
                                  "aligned poses; the identification's memory grows with them)");
    }
    const std::vector<std::string> f = SplitCsv(line);
    if (f.size() != header.size()) {
      throw InputError(where, "expected " + std::to_string(header.size()) + " fields, got " +
                                  std::to_string(f.size()));
    }
    if (out.robot.empty()) {
      out.robot = f[col["robot"]];
      RequireSafeName(out.robot, where + " robot", "robot name");
    }
    if (f[col["robot"]] != out.robot) continue;
    const auto cell = [&](const char* key) { return f[col.at(key)]; };
    // An optional figure: NaN where the column is missing or the field empty.
    const auto optional = [&](const char* key) {
      return col.count(key) && !cell(key).empty() ? CsvNumber(cell(key), where + " " + key)
                                                  : MeasurementRow::kNone;
    };
    const auto optional_count = [&](const char* key) {
      return col.count(key) && !cell(key).empty() ? CsvInteger(cell(key), where + " " + key) : -1;
    };
    MeasurementRow r;
    r.robot = out.robot;
    if (col.count("camera_robot")) r.camera_robot = cell("camera_robot");
    r.axis = CsvInteger(cell("axis"), where + " axis");
    if (r.axis >= kMaxMeasurementAxes) {
      throw InputError(where + " axis", "expected an axis index below " +
                                            std::to_string(kMaxMeasurementAxes) +
                                            " (each axis adds unknowns to the identification), "
                                            "got " + cell("axis"));
    }
    r.index = CsvInteger(cell("index"), where + " index");
    r.q = JointVector::Zero(joints);
    for (int i = 0; i < joints; ++i) {
      const std::string key = "q" + std::to_string(i + 1) + "_deg";
      const double deg = CsvNumber(f[col[key]], where + " " + key);
      if (std::abs(deg) > 720.0) {
        throw InputError(where + " " + key, "expected a joint angle within +-720 deg (two turns), "
                                            "got '" + f[col[key]] + "'");
      }
      r.q(i) = DegToRad(deg);
    }
    if (out.has_depth && !cell("depth_mm").empty()) {
      const double depth_mm = CsvNumber(cell("depth_mm"), where + " depth_mm");  // empty: none
      if (!(depth_mm > 0.0 && depth_mm <= 10000.0)) {
        throw InputError(where + " depth_mm", "expected a camera depth in (0, 10000] mm, got '" +
                                                  cell("depth_mm") + "'");
      }
      r.depth_m = depth_mm / 1000.0;
    }
    if (out.has_offset) {
      r.offset = Vector3(CsvNumber(cell("offset_x_mm"), where + " offset_x_mm"),
                         CsvNumber(cell("offset_y_mm"), where + " offset_y_mm"),
                         CsvNumber(cell("offset_z_mm"), where + " offset_z_mm")) /
                 1000.0;
      if (r.offset.norm() > 1.0) {
        throw InputError(where + " offset_x_mm", "the residual offset from the axis must be "
                                                 "below 1000 mm (the servo aligns to a pixel), "
                                                 "got " + std::to_string(1e3 * r.offset.norm()) +
                                                 " mm");
      }
    }
    r.du_px = optional("du_px");
    r.dv_px = optional("dv_px");
    r.frames = optional_count("frames");
    r.moves = optional_count("moves");
    r.du0_px = optional("du0_px");
    r.dv0_px = optional("dv0_px");
    r.pose_rms_px = optional("pose_rms_px");
    r.time_s = optional("time_s");
    r.temperature_delta_K = optional("temperature_delta_K");
    r.set = cell("set");
    if (r.set == "calibration") {
      cal_axes.insert(r.axis);
    } else if (r.set == "validation") {
      val_axes.insert(r.axis);
    } else if (r.set != "unused") {
      throw InputError(where + " set", "expected calibration, validation or unused, got '" +
                                           r.set + "'");
    }
    out.rows.push_back(std::move(r));
    out.lines.push_back(line_number);
  }
  if (out.rows.empty()) throw InputError(path, "no rows for robot '" + out.robot + "'");
  for (int k : cal_axes) {
    if (val_axes.count(k)) {
      throw InputError(path, "axis " + std::to_string(k) +
                                 " has rows in both the calibration and the validation set; "
                                 "split by whole axes");
    }
  }
  return out;
}

}  // namespace twin
