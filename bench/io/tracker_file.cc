#include "bench/io/tracker_file.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "bench/io/csv.h"
#include "bench/io/yaml_util.h"
#include "bench/io/output_files.h"
#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"

namespace twin {
namespace {

constexpr std::uintmax_t kMaxTrackerBytes = std::uintmax_t{64} << 20;
constexpr std::size_t kMaxTrackerLine = 4096;
constexpr double kMaxReflectorDistance = 100.0;  // [m] beyond any tracker's range (~80 m)
constexpr double kMaxSigma = 0.01;               // [m] a tracker states micrometres
constexpr double kMaxJointReading = 4 * 3.14159265358979323846;  // two turns [rad]

// A unit suffix of a column name: the scale to SI, or nullopt when `name` is not base + unit.
std::optional<double> UnitScale(const std::string& name, const std::string& base,
                                const std::vector<std::pair<std::string, double>>& units) {
  for (const auto& [suffix, scale] : units) {
    if (name == base + "_" + suffix) return scale;
  }
  return std::nullopt;
}

// Most a row's stated sigma may differ from the file's median, either way: a tracker's stated
// uncertainty grows with distance and angle (a few times across a cell; 62 times between the
// extremes and under 10 times from the median in the real Leica session), so 100 only catches
// typos and units, like one row at 1e-300 m that would outweigh all the others together.
constexpr double kSigmaFactor = 100.0;
// Most the reflector's spread may differ from the spread of the nominal model's end frame over
// the same joint readings: a tool offset and the real geometry change it by tens of percent,
// a unit error (metres labelled mm) by 1000 times. Spreads under kMinSpread are not compared.
constexpr double kSpreadFactor = 10.0;
constexpr double kMinSpread = 0.02;  // [m]
// Largest range of an ignored joint column (one held constant and merged into the base):
// a braked axis reads within a few encoder counts (2.7e-4 rad in the real session's torso),
// so 2e-3 rad (0.11 deg) is a constant axis and more is a moving one.
constexpr double kMaxConstantRange = 2e-3;  // [rad]

// RMS distance of the points from their centroid [m].
double Spread(const std::vector<Vector3>& p) {
  Vector3 c = Vector3::Zero();
  for (const Vector3& v : p) c += v;
  c /= static_cast<double>(p.size());
  double ss = 0.0;
  for (const Vector3& v : p) ss += (v - c).squaredNorm();
  return std::sqrt(ss / static_cast<double>(p.size()));
}

// The whole-file checks, with the reason in the message: sigmas within kSigmaFactor of their
// median, a position unit that agrees with the motion, ignored joint columns constant, and
// repeated poses counted as such (TrackerFile::pose_group).
void CheckPlausibility(const std::string& path, const KinematicModel& model,
                       const std::vector<std::string>& header, int x_col, double xyz_scale,
                       int sigma_col, TrackerFile* out) {
  const std::vector<TrackerPoint>& pts = out->points;
  if (sigma_col >= 0) {
    std::vector<double> s;
    for (const TrackerPoint& p : pts) s.push_back(p.sigma);
    std::nth_element(s.begin(), s.begin() + s.size() / 2, s.end());
    const double median = s[s.size() / 2];
    for (const TrackerPoint& p : pts) {
      if (p.sigma < median / kSigmaFactor || p.sigma > median * kSigmaFactor) {
        std::ostringstream os;
        os << "sigma " << p.sigma << " m is more than " << kSigmaFactor << " times "
           << (p.sigma < median ? "below" : "above") << " the file's median sigma " << median
           << " m; such a row would " << (p.sigma < median ? "outweigh all the others together "
                                                             "and drop the identification's rank"
                                                           : "count for nothing")
           << " (fix the row or its unit)";
        throw InputError(path + ":" + std::to_string(p.row) + " column " +
                             std::to_string(sigma_col + 1) + " (" + header[sigma_col] + ")",
                         os.str());
      }
    }
  }
  if (pts.size() >= 3) {
    std::vector<Vector3> measured, predicted;
    for (const TrackerPoint& p : pts) {
      measured.push_back(p.p_T);
      predicted.push_back(EndPose(model, p.context.q).translation());
    }
    const double m = Spread(measured), e = Spread(predicted);
    if (e > kMinSpread && (m > kSpreadFactor * e || m * kSpreadFactor < e)) {
      const bool mm = xyz_scale < 1.0;
      std::ostringstream os;
      os << "the reflector positions spread " << (mm ? m * 1e3 : m) << (mm ? " mm" : " m")
         << " about their centre, but the nominal model's end frame spreads " << e * 1e3
         << " mm over the same joint readings (" << m / e << " times): the values look like "
         << (m < e ? (mm ? "metres; name the columns x_m, y_m, z_m"
                         : "millimetres divided by 1000 twice; check the unit")
                   : (mm ? "micrometres; check the unit" : "millimetres; name the columns x_mm, "
                                                           "y_mm, z_mm"));
      throw InputError(path + ":1 column " + std::to_string(x_col + 1) + " (" + header[x_col] + ")",
                       os.str());
    }
  }
  for (const TrackerFileColumn& c : out->ignored) {
    const bool rad = c.name.size() > 4 && c.name.compare(c.name.size() - 4, 4, "_rad") == 0;
    const bool deg = c.name.size() > 4 && c.name.compare(c.name.size() - 4, 4, "_deg") == 0;
    if (c.name.rfind("q", 0) != 0 || !(rad || deg)) continue;
    const double range = (c.max - c.min) * (deg ? 3.14159265358979323846 / 180.0 : 1.0);
    if (range > kMaxConstantRange) {
      std::ostringstream os;
      os << "an ignored joint column must be constant (the axis held still and merged into the "
            "model's base), but it ranges over " << c.max - c.min << (deg ? " deg" : " rad")
         << " (" << c.min << " to " << c.max << "; at most " << kMaxConstantRange
         << " rad is a braked axis); model that joint instead of ignoring it";
      throw InputError("--ignore-column " + c.name, os.str());
    }
  }
  // Repeated poses: counted as repeats, not as independent points.
  out->pose_group = PoseGroups(pts);
  out->distinct_poses = pts.empty() ? 0 : *std::max_element(out->pose_group.begin(),
                                                             out->pose_group.end()) + 1;
}

}  // namespace

bool IsTrackerFile(const std::string& path) {
  // Checked before it is opened: a FIFO would block the open, /dev/zero would never end a line.
  RequireRegularFile(path, kMaxTrackerBytes);
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line)) return false;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  for (const std::string& c : SplitCsv(line)) {
    if (c == "x_m" || c == "x_mm") return true;
  }
  return false;
}

TrackerFile ReadTrackerFile(const std::string& path, const KinematicModel& model,
                            const std::vector<std::string>& ignore) {
  RequireRegularFile(path, kMaxTrackerBytes);
  NoteInput(path);
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot read the tracker file");
  TrackerFile out;
  out.path = path;
  std::string line;
  if (!std::getline(in, line)) throw InputError(path, "empty file (expected a header line)");
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const std::string head = path + ":1";
  if (line.size() > kMaxTrackerLine) {
    throw InputError(head, "header longer than " + std::to_string(kMaxTrackerLine) + " characters");
  }
  const std::vector<std::string> header = SplitCsv(line);
  std::map<std::string, int> col;
  for (int i = 0; i < static_cast<int>(header.size()); ++i) {
    if (header[i].empty()) throw InputError(head, "column " + std::to_string(i + 1) + " has no name");
    if (!col.emplace(header[i], i).second) {
      throw InputError(head, "column '" + header[i] + "' appears twice");
    }
  }
  for (const std::string& c : ignore) {
    if (!col.count(c)) throw InputError("--ignore-column", "the file has no column '" + c + "'");
  }

  // Joint columns in model order: q_<link name>_<unit> or q<k>_<unit>.
  const std::vector<std::pair<std::string, double>> angle_units = {{"rad", 1.0},
                                                                   {"deg", 3.14159265358979323846 / 180.0}};
  const int n = model.num_joints();
  std::vector<int> joint_col(n, -1);
  std::vector<double> joint_scale(n, 1.0);
  std::set<int> used;
  for (int j = 0; j < n; ++j) {
    for (const auto& [name, i] : col) {
      for (const std::string& base :
           {"q_" + model.links[j].name, "q" + std::to_string(j + 1)}) {
        if (const auto s = UnitScale(name, base, angle_units)) {
          if (joint_col[j] >= 0) {
            throw InputError(head, "joint " + std::to_string(j + 1) + " (" + model.links[j].name +
                                       ") has two columns: '" + header[joint_col[j]] + "' and '" +
                                       name + "'");
          }
          joint_col[j] = i;
          joint_scale[j] = *s;
        }
      }
    }
    if (joint_col[j] < 0) {
      throw InputError(head, "missing the column of joint " + std::to_string(j + 1) + " of " +
                                 std::to_string(n) + " ('q_" + model.links[j].name + "_rad', 'q" +
                                 std::to_string(j + 1) + "_deg' or the like)");
    }
    used.insert(joint_col[j]);
    out.joint_columns.push_back(header[joint_col[j]]);
  }
  // Position, sigma, time, temperature.
  const std::vector<std::pair<std::string, double>> length_units = {{"m", 1.0}, {"mm", 1e-3}};
  int xyz_col[3] = {-1, -1, -1};
  double xyz_scale = 1.0;
  int sigma_col = -1, time_col = -1, temp_col = -1, pose_col = -1;
  double sigma_scale = 1.0;
  for (const auto& [name, i] : col) {
    for (int k = 0; k < 3; ++k) {
      if (const auto s = UnitScale(name, std::string(1, "xyz"[k]), length_units)) {
        xyz_col[k] = i;
        if (k > 0 && *s != xyz_scale) {
          throw InputError(head, "x, y and z must have the same unit ('" + name + "')");
        }
        xyz_scale = *s;
      }
    }
    if (const auto s = UnitScale(name, "sigma", length_units)) {
      sigma_col = i;
      sigma_scale = *s;
    }
    if (name == "time_s") time_col = i;
    if (name == "temperature_delta_K") temp_col = i;
    if (name == "pose") pose_col = i;
  }
  for (int k = 0; k < 3; ++k) {
    if (xyz_col[k] < 0) {
      throw InputError(head, std::string("missing the column '") + "xyz"[k] +
                                 "_m' (or _mm): the reflector position in the tracker frame");
    }
    used.insert(xyz_col[k]);
  }
  for (int c : {sigma_col, time_col, temp_col, pose_col}) {
    if (c >= 0) used.insert(c);
  }
  std::vector<int> ignored_cols;
  for (const std::string& c : ignore) {
    if (used.count(col[c])) {
      throw InputError("--ignore-column", "'" + c + "' is a column the identification reads");
    }
    ignored_cols.push_back(col[c]);
    used.insert(col[c]);
    out.ignored.push_back({c, INFINITY, -INFINITY});
  }
  for (int i = 0; i < static_cast<int>(header.size()); ++i) {
    if (used.count(i)) continue;
    std::string hint;
    if (header[i].rfind("q", 0) == 0) {
      hint = " (a joint the " + std::to_string(n) + "-joint model lacks; if it is held constant "
             "and merged into the model's base, pass --ignore-column " + header[i] + ")";
    }
    throw InputError(head + " column " + std::to_string(i + 1),
                     "unknown column '" + header[i] + "'" + hint +
                         "; expected pose, q_<joint>_rad/_deg, x/y/z_m or _mm, sigma_m or "
                         "_mm, time_s, temperature_delta_K");
  }
  out.has_sigma = sigma_col >= 0;
  out.has_time = time_col >= 0;
  out.has_temperature = temp_col >= 0;

  int line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::string where = path + ":" + std::to_string(line_number);
    if (line.size() > kMaxTrackerLine) {
      throw InputError(where, "line longer than " + std::to_string(kMaxTrackerLine) + " characters");
    }
    if (line.empty()) continue;
    if (static_cast<int>(out.points.size()) >= kMaxTrackerRows) {
      throw InputError(where, "more than " + std::to_string(kMaxTrackerRows) + " tracker rows");
    }
    const std::vector<std::string> f = SplitCsv(line);
    if (f.size() != header.size()) {
      throw InputError(where, "expected " + std::to_string(header.size()) + " fields (as the "
                              "header), got " + std::to_string(f.size()));
    }
    const auto cell = [&](int c) {
      return CsvNumber(f[c], where + " column " + std::to_string(c + 1) + " (" + header[c] + ")");
    };
    TrackerPoint p;
    p.row = line_number;
    p.context.q = ZeroJoints(model);
    for (int j = 0; j < n; ++j) {
      const double v = cell(joint_col[j]) * joint_scale[j];
      if (std::abs(v) > kMaxJointReading) {
        throw InputError(where + " column " + std::to_string(joint_col[j] + 1) + " (" +
                             header[joint_col[j]] + ")",
                         "a joint reading beyond two turns (check the unit in the column name)");
      }
      p.context.q(j) = v;
    }
    for (int k = 0; k < 3; ++k) p.p_T(k) = cell(xyz_col[k]) * xyz_scale;
    if (p.p_T.norm() > kMaxReflectorDistance) {
      throw InputError(where, "the reflector lies beyond 100 m of the tracker (check the unit "
                              "in the column names)");
    }
    if (sigma_col >= 0) {
      p.sigma = cell(sigma_col) * sigma_scale;
      if (!(p.sigma > 0.0 && p.sigma <= kMaxSigma)) {
        throw InputError(where + " column " + std::to_string(sigma_col + 1) + " (" +
                             header[sigma_col] + ")",
                         "expected a sigma in (0, 10] mm");
      }
    }
    if (time_col >= 0) p.context.time_s = cell(time_col);
    if (temp_col >= 0) p.context.temperature_delta_K = cell(temp_col);
    for (std::size_t k = 0; k < ignored_cols.size(); ++k) {
      const double v = cell(ignored_cols[k]);
      out.ignored[k].min = std::min(out.ignored[k].min, v);
      out.ignored[k].max = std::max(out.ignored[k].max, v);
    }
    out.pose_ids.push_back(pose_col >= 0 ? f[pose_col] : std::to_string(out.points.size() + 1));
    out.points.push_back(std::move(p));
  }
  if (out.points.empty()) throw InputError(path, "no data rows after the header");
  CheckPlausibility(path, model, header, xyz_col[0], xyz_scale, sigma_col, &out);
  return out;
}

}  // namespace twin
