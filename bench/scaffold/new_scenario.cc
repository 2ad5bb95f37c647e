#include "bench/scaffold/new_scenario.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "bench/io/calibration_config.h"
#include "bench/io/output_files.h"
#include "bench/io/scenario.h"
#include "bench/io/scenario_keys.h"
#include "bench/io/yaml_util.h"
#include "bench/report/acceptance.h"
#include "bench/runs/handclasp_run.h"
#include "bench/runs/tracker_run.h"
#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "calib/kinematics/inverse_kinematics.h"
#include "calib/procedures/optical_axis_procedure.h"
#include "sim/cell/twin_cell.h"
#include "sim/world/mujoco_handles.h"

namespace twin {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// The stated rough amounts: the truth differs from what the estimator is told by these, the
// amounts of the shipped scenarios (scenarios/paper_reinovo.yaml, section VI.B of Zhu et al.
// 2019; tracker_reinovo.yaml). Poses of tools are in the flange-out frame F' (z out of the face).
namespace {

constexpr double kWorkingDistanceMm = 400.0;  // camera to board at the start pose (paper: 0.4 m)
// Base-to-base: told (D, 0, 0) mm, ZYZ (180, 0, 0) deg; true off by these.
constexpr double kBaseOffsetMm[3] = {3.2, -2.6, 0.8};
constexpr double kBaseZyzDeg[3] = {179.7, 0.2, -0.1};
// Hand-eye in F': told (60, -60, 34) mm, no rotation (the camera on a bracket 34 mm in front of
// the face, as abb_irb2400.yaml: further back, the housing touches link 4 when the wrist
// bends); true off by (2.1, 1.6, 1.7) mm and RPY (0.8, -0.6, 1.1) deg.
constexpr double kToldHandEyeMm[3] = {60, -60, 34};
constexpr double kTrueHandEyeMm[3] = {62.1, -58.4, 35.7};
constexpr double kTrueHandEyeRpyDeg[3] = {0.8, -0.6, 1.1};
// Board 40 mm in front of the face (made to its drawing: told = true).
constexpr double kBoardMountMm[3] = {0, 0, 40};
// Reflector in F': told (40, -30, 80) mm by drawing, true (40.6, -29.2, 80.9) as built.
constexpr double kToldReflectorMm[3] = {40, -30, 80};
constexpr double kTrueReflectorMm[3] = {40.6, -29.2, 80.9};

std::string Num(double x, int precision = 1) {
  if (std::abs(x) < 0.5 * std::pow(10.0, -precision)) x = 0.0;  // no "-0.0"
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", precision, x);
  return buf;
}

std::string List(const Vector3& v, int precision = 1) {
  return "[" + Num(v.x(), precision) + ", " + Num(v.y(), precision) + ", " +
         Num(v.z(), precision) + "]";
}

Vector3 Mm(const double (&v)[3]) { return Vector3(v[0], v[1], v[2]); }

Matrix3 Rpy(const double (&deg)[3]) {
  return RpyToRotation(Vector3(DegToRad(deg[0]), DegToRad(deg[1]), DegToRad(deg[2])));
}

Matrix3 Zyz(const double (&deg)[3]) {
  return (Eigen::AngleAxisd(DegToRad(deg[0]), Vector3::UnitZ()) *
          Eigen::AngleAxisd(DegToRad(deg[1]), Vector3::UnitY()) *
          Eigen::AngleAxisd(DegToRad(deg[2]), Vector3::UnitZ()))
      .toRotationMatrix();
}

// Roll, pitch, yaw [deg] of R = Rz(y) Ry(p) Rx(r) (fixed axes, the scenario's rpy_deg).
Vector3 RpyDeg(const Matrix3& R) {
  const double p = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  return Vector3(RadToDeg(std::atan2(R(2, 1), R(2, 2))), RadToDeg(p),
                 RadToDeg(std::atan2(R(1, 0), R(0, 0))));
}

Transform MakePose(const Vector3& xyz_mm, const Matrix3& R) {
  Transform X = Transform::Identity();
  X.translation() = xyz_mm * 1e-3;
  X.linear() = R;
  return X;
}

// A pose map of the scenario format: {xyz_mm: [..], rpy_deg: [..]}.
std::string PoseMap(const Transform& X) {
  return "{xyz_mm: " + List(X.translation() * 1e3) + ", rpy_deg: " + List(RpyDeg(X.linear())) +
         "}";
}

}  // namespace

Transform FlangeOutFrame(const KinematicModel& model) {
  const FrameSet f = ForwardKinematics(model, ZeroJoints(model));
  const double along = f.flange().linear().col(2).dot(f.X_BE.linear().col(2));
  const bool into_wrist = std::abs(along) > 0.5 ? along < 0 : model.flange().dh.d < 0;
  Transform X = Transform::Identity();
  if (into_wrist) X.linear() = Eigen::AngleAxisd(kPi, Vector3::UnitX()).toRotationMatrix();
  return X;
}

KinematicModel FlangeOnlyModel(const KinematicModel& model) {
  KinematicModel m = model;
  m.tool().dh = DhParameters{};
  m.X_LtE = Transform::Identity();
  return m;
}

double HorizontalReach(const KinematicModel& model, int samples) {
  std::mt19937_64 rng(1);
  double reach = 0.0;
  JointVector q(model.num_joints());
  for (int k = 0; k < samples; ++k) {
    for (int i = 0; i < model.num_joints(); ++i) {
      const JointLimits& l = model.links[i].limits;
      q(i) = std::uniform_real_distribution<double>(l.lower, l.upper)(rng);
    }
    const Vector3 p = ForwardKinematics(model, q).flange().translation();
    reach = std::max(reach, std::hypot(p.x(), p.y()));
  }
  return reach;
}

namespace {

// One arm of the cell: its model file and what the cell derives from it.
struct Arm {
  std::string path;        // as given on the command line
  ModelLinks links;        // as given (tip_link filled in where the import chose one)
  KinematicModel model;    // nominal
  Transform X_LF;          // flange-out frame F' in L_N (FlangeOutFrame)
  double reach = 0.0;      // HorizontalReach [m]
  double shoulder_z = 0;   // height of DH frame L1's origin at q = 0 [m]
};

Arm LoadArm(const std::string& path, const ModelLinks& links, const std::string& option) {
  if (path.empty()) throw InputError(option, "expected a robot model file (.yaml, .yml or .urdf)");
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw InputError(option, "'" + path + "' does not exist or is not a file; expected a robot "
                             "model file (.yaml, .yml or .urdf)");
  }
  Arm arm;
  arm.path = path;
  arm.links = links;
  std::vector<std::string> warnings;
  arm.model = LoadRobotModel(path, links, &warnings);
  // The import's automatic tip (a ROS-Industrial URDF's tool0), written out explicitly.
  for (const std::string& w : warnings) {
    const std::size_t at = w.find("chose '");
    if (arm.links.tip_link.empty() && at != std::string::npos) {
      const std::size_t end = w.find('\'', at + 7);
      arm.links.tip_link = w.substr(at + 7, end - at - 7);
    }
  }
  if (arm.model.num_joints() != kDefaultJoints) {
    throw InputError(option, "'" + path + "' has " + std::to_string(arm.model.num_joints()) +
                                 " joints; expected a six-axis arm (a scenario's "
                                 "initial_joints_deg holds 6 angles)");
  }
  arm.X_LF = FlangeOutFrame(arm.model);
  arm.reach = HorizontalReach(arm.model);
  arm.shoulder_z = ForwardKinematics(arm.model, ZeroJoints(arm.model)).X_BL[1].translation().z();
  return arm;
}

// The cell: where the two arms stand and how they start.
struct Layout {
  double fraction = 0.6;     // where camera and board meet: this part of the reach out
  double distance_mm = 0;    // D: told base-to-base distance
  double height_mm = 0;      // camera and board height above the floor
  double camera_out_mm = 0;  // the camera's distance from base 1 along the base line
  Transform X_B1B2_true = Transform::Identity();
  Transform X_FC_true = Transform::Identity(), X_FT = Transform::Identity();
  JointVector q1, q2;        // initial joints [rad]
  bool mid_range = false;    // q1, q2 the middle of each joint's range (camera, board apart)
  double score = -1;         // the smaller of the two arms' pose scores
  double sv1 = 0, sv2 = 0, margin1 = 0, margin2 = 0;  // manipulability, limit margin [deg]
};

// Distance of q from the nearest joint limit [deg].
double LimitMarginDeg(const KinematicModel& m, const JointVector& q) {
  double margin = 1e9;
  for (int i = 0; i < m.num_joints(); ++i) {
    margin = std::min({margin, q(i) - m.links[i].limits.lower, m.links[i].limits.upper - q(i)});
  }
  return RadToDeg(margin);
}

struct PoseChoice {
  JointVector q;
  double score = -1, sv = 0, margin = 0;
};

// Whether the elbow (the origin of DH frame L2, joint 3's axis) stands above the shoulder
// (L1) by a tenth of the upper arm at `q`: the posture arms work in. An arm whose upper arm
// lies level or hangs (a UR's shoulder at -180 deg) is a small move away from its own base.
bool ElbowUp(const KinematicModel& m, const JointVector& q) {
  const FrameSet fk = ForwardKinematics(m, q);
  const Vector3 shoulder = fk.X_BL[1].translation(), elbow = fk.X_BL[2].translation();
  return elbow.z() - shoulder.z() > 0.1 * (elbow - shoulder).norm();
}

// The best IK solution of `end_model` for `target` turned about its z by 0, 90, 180, 270 deg,
// from three IK seeds each: elbow up where one is (ElbowUp), then the largest smallest
// Jacobian singular value, weighed down within 40 deg of a joint limit (the planner's C1 keeps
// 10 deg; the pose must leave room to move).
PoseChoice BestPose(const KinematicModel& end_model, const Transform& target) {
  PoseChoice best, best_up;
  // IK from `start` for the four rolls; the restarts' seeds 1..3 where the start fails. From a
  // random start a solution is turned by whole turns to the angles nearest the limits' middle
  // (-310 deg written as 50).
  const auto search = [&](const JointVector& start, bool random_start) {
    for (int roll = 0; roll < 4; ++roll) {
      Transform X = target;
      X.linear() = target.linear() * Eigen::AngleAxisd(roll * kPi / 2, Vector3::UnitZ()).matrix();
      for (std::uint64_t seed = 1; seed <= 3; ++seed) {
        IkOptions o;
        o.seed = seed;
        IkResult r = SolveIk(end_model, X, start, o);
        if (r.status != IkStatus::kSuccess) continue;
        if (random_start) r.q = NearestTurns(end_model, r.q, MidRange(end_model));
        const double margin = LimitMarginDeg(end_model, r.q);
        const double sv = SmallestJacobianSingularValue(end_model, r.q);
        const double score = sv * std::min(1.0, margin / 40.0);
        if (margin < 15.0) continue;
        if (score > best.score) best = PoseChoice{r.q, score, sv, margin};
        if (score > best_up.score && ElbowUp(end_model, r.q)) {
          best_up = PoseChoice{r.q, score, sv, margin};
        }
      }
    }
  };
  search(MidRange(end_model), false);
  // No elbow-up solution from the middle of the limits (a UR's all-zero middle is the arm
  // stretched out level): the IK from 16 seeded random starts inside the limits too.
  if (best_up.score < 0) {
    std::mt19937_64 rng(2019);
    for (int k = 0; k < 16; ++k) {
      JointVector q = MidRange(end_model);
      for (int i = 0; i < end_model.num_joints(); ++i) {
        const JointLimits& l = end_model.links[i].limits;
        q(i) = std::uniform_real_distribution<double>(l.lower, l.upper)(rng);
      }
      search(q, true);
    }
  }
  return best_up.score >= 0 ? best_up : best;
}

// The cell's frames (no initial joints): bases `distance_mm` apart, camera and board meeting
// `fraction` of the reach out at `height`.
Layout CellFrames(const Arm& a1, const Arm& a2, double fraction, double distance_mm,
                  double height_m) {
  Layout c;
  c.fraction = fraction;
  c.distance_mm = distance_mm;
  c.height_mm = 10.0 * std::round(height_m * 100.0);
  c.camera_out_mm = 0.5 * (c.distance_mm - kWorkingDistanceMm);
  c.X_B1B2_true = MakePose(Vector3(c.distance_mm, 0, 0) + Mm(kBaseOffsetMm), Zyz(kBaseZyzDeg));
  c.X_FC_true = a1.X_LF * MakePose(Mm(kTrueHandEyeMm), Rpy(kTrueHandEyeRpyDeg));
  c.X_FT = a2.X_LF * MakePose(Mm(kBoardMountMm), Matrix3::Identity());
  return c;
}

// The cell of bases `distance_mm` apart whose camera and board meet `fraction` of the reach
// out (D = 2 f R + w) at `height`.
Layout SolveCell(const Arm& a1, const Arm& a2, double fraction, double distance_mm,
                 double height_m) {
  Layout c = CellFrames(a1, a2, fraction, distance_mm, height_m);
  // Camera (OpenCV: z forward, y down) looking along base 1's x at robot 2; the board's
  // outward normal (its z) back along the optical axis, w further on.
  Matrix3 R_C;
  R_C.col(0) = -Vector3::UnitY();
  R_C.col(1) = -Vector3::UnitZ();
  R_C.col(2) = Vector3::UnitX();
  Matrix3 R_T;
  R_T.col(0) = -Vector3::UnitY();
  R_T.col(1) = Vector3::UnitZ();
  R_T.col(2) = -Vector3::UnitX();
  const Transform X_B1C = MakePose(Vector3(c.camera_out_mm, 0, c.height_mm), R_C);
  const Transform X_B1T =
      MakePose(Vector3(c.camera_out_mm + kWorkingDistanceMm, 0, c.height_mm), R_T);
  const PoseChoice p1 = BestPose(BoardRobotModel(a1.model, c.X_FC_true), X_B1C);
  const PoseChoice p2 =
      BestPose(BoardRobotModel(a2.model, c.X_FT), c.X_B1B2_true.inverse() * X_B1T);
  if (p1.score < 0 || p2.score < 0) return c;
  c.q1 = p1.q;
  c.q2 = p2.q;
  c.sv1 = p1.sv;
  c.sv2 = p2.sv;
  c.margin1 = p1.margin;
  c.margin2 = p2.margin;
  c.score = std::min(p1.score, p2.score);
  return c;
}

// The cells of bases `distance_mm` apart (camera and board meeting `fraction` of the reach
// out), at the shoulder's height and 0.25, 0.5 of the reach above it (never below 0.4 m off the
// floor), appended to `cells` where IK found both start poses.
void AddCellsAt(const Arm& a1, const Arm& a2, double fraction, double distance_mm,
                std::vector<Layout>* cells) {
  const double reach = 0.5 * (a1.reach + a2.reach);
  const double shoulder = 0.5 * (a1.shoulder_z + a2.shoulder_z);
  for (double up : {0.0, 0.25, 0.5}) {
    Layout c = SolveCell(a1, a2, fraction, distance_mm, std::max(0.4, shoulder + up * reach));
    if (c.score > 0) cells->push_back(c);
  }
}

void SortByScore(std::vector<Layout>* cells) {
  std::stable_sort(cells->begin(), cells->end(),
                   [](const Layout& x, const Layout& y) { return x.score > y.score; });
}

// Candidate cells, best first: the meeting point at 0.5, 0.6, 0.7 of the reach out (D = 2 f R
// + w rounded to 10 mm), at the heights of AddCellsAt.
std::vector<Layout> CandidateCells(const Arm& a1, const Arm& a2) {
  std::vector<Layout> cells;
  const double reach = 0.5 * (a1.reach + a2.reach);
  for (double fraction : {0.5, 0.6, 0.7}) {
    const double distance_mm =
        10.0 * std::round((2 * fraction * reach * 1e3 + kWorkingDistanceMm) / 10.0);
    AddCellsAt(a1, a2, fraction, distance_mm, &cells);
  }
  SortByScore(&cells);
  return cells;
}

// ---------------------------------------------------------------------------------------------
// The handclasp cell. The run's planner (bench/runs/handclasp_run.h, TeachHandclaspPoints)
// puts its contacts on the corners of a cube centred between the two shoulders, robot 1's tip
// pointing at robot 2's shoulder, and needs 6 corners that both arms reach with their tips
// (and robot 2 its stand-off) inside the joint limits, by IK started from the encoders. That
// depends on D and the tip length (the cube sits at the shoulders' height, lifted to 150 mm
// off the floor) and on the start pose, not on where the camera meets the board: with the
// optical-axis cell's D = 2 f R + w and start poses, 200 mm tips on 0.85 m arms (reinovo_r2,
// D = 1250 mm) taught 4 of 8 corners of the smallest cube (the flanges folded back towards
// the bases; from the camera-and-board poses the IK ended beyond the joint limits). Too far
// apart, the corners are out of reach. So D is searched with the planner itself from the
// joints' mid-range (the file's initial joints), and the best candidates are tried on the
// twin: the planner knows the limits, not the links, and a folded arm may touch itself.
constexpr double kHandclaspTipMm = 200.0;  // as scenarios/gan2014_*.yaml
constexpr int kHandclaspSeed = 11;          // the scenario's seed: the planner's IK restarts
// Where the tips meet: g of the reach out from each base (D = 2 g R), g on this grid.
constexpr double kMeetFirst = 0.40, kMeetStep = 0.05;
constexpr int kMeetCount = 15;  // 0.40 .. 1.10
constexpr int kMeetsTried = 6;  // the best meeting points tried on the twin

// The handclasp's tip on an arm's flange: `tip_mm` out of the face (in L_N).
Transform HandclaspTip(const Arm& a, double tip_mm) {
  return a.X_LF * MakePose(Vector3(0, 0, tip_mm), Matrix3::Identity());
}

// One meeting point of the tips and the cube the planner takes there.
struct Meeting {
  double g = 0;            // the tips meet g R out from each base
  double distance_mm = 0;  // D = 2 g R, rounded to 10 mm
  double side_m = 0;       // the planner's cube side [m] (0: no cube)
  double worst_m = 0;      // the smallest of side_m at this D and one grid step each way
};

// The planner's cube side [m] for bases D apart as drawn (the told layout: (D, 0, 0), ZYZ
// (180, 0, 0)) and the told tips, on the nominal models from their mid-range joints; 0 where
// no cube has 6 teachable corners.
double PlannedCubeSide(const Arm& a1, const Arm& a2, double distance_mm, double tip_mm) {
  HandclaspConfig config;
  config.rough_X_B1B2 = MakePose(Vector3(distance_mm, 0, 0),
                                 Eigen::AngleAxisd(kPi, Vector3::UnitZ()).toRotationMatrix());
  config.told_X_FTip = {HandclaspTip(a1, tip_mm), HandclaspTip(a2, tip_mm)};
  TeachOptions options;
  options.seed = kHandclaspSeed;
  const TaughtPoints t = TeachHandclaspPoints(config, {a1.model, a2.model},
                                              {MidRange(a1.model), MidRange(a2.model)}, options);
  return t.ok ? t.cube_side_m : 0.0;
}

// The meeting points with a cube, best first: the largest cube that D one grid step shorter
// and longer keep too (the planner's IK is sensitive to the exact D: a point between two good
// ones may fail), then the largest cube, then the shorter D.
std::vector<Meeting> HandclaspMeetings(const Arm& a1, const Arm& a2, double tip_mm) {
  const double reach = 0.5 * (a1.reach + a2.reach);
  std::vector<Meeting> grid(kMeetCount);
  for (int i = 0; i < kMeetCount; ++i) {
    grid[i].g = kMeetFirst + i * kMeetStep;
    grid[i].distance_mm = 10.0 * std::round(2 * grid[i].g * reach * 1e2);
    grid[i].side_m = PlannedCubeSide(a1, a2, grid[i].distance_mm, tip_mm);
  }
  std::vector<Meeting> meetings;
  for (int i = 0; i < kMeetCount; ++i) {
    Meeting m = grid[i];
    m.worst_m = std::min({i > 0 ? grid[i - 1].side_m : 0.0, m.side_m,
                          i + 1 < kMeetCount ? grid[i + 1].side_m : 0.0});
    if (m.side_m > 0) meetings.push_back(m);
  }
  std::stable_sort(meetings.begin(), meetings.end(), [](const Meeting& x, const Meeting& y) {
    return x.worst_m != y.worst_m ? x.worst_m > y.worst_m : x.side_m > y.side_m;
  });
  return meetings;
}

// Where a lone arm (a one-robot tracker cell) starts: its flange face out along base x at
// `fraction` of the reach out and `height_mm` up, at the pose BestPose chose.
struct ArmStart {
  double fraction = 0.6;
  double height_mm = 0;
  PoseChoice pose;
};

// Start poses of a lone arm, best first: the flange-out frame F' with its z along base x at
// 0.5, 0.6, 0.7 of the reach out, at the shoulder's height and 0.25, 0.5 of the reach above
// it (never below 0.4 m off the floor), as CandidateCells places robot 1's camera.
std::vector<ArmStart> CandidateStarts(const Arm& a) {
  Matrix3 R;  // F' z out along base x
  R.col(0) = Vector3::UnitY();
  R.col(1) = Vector3::UnitZ();
  R.col(2) = Vector3::UnitX();
  const KinematicModel end_model = BoardRobotModel(a.model, a.X_LF);
  std::vector<ArmStart> starts;
  for (double fraction : {0.5, 0.6, 0.7}) {
    for (double up : {0.0, 0.25, 0.5}) {
      ArmStart start;
      start.fraction = fraction;
      start.height_mm = 10.0 * std::round(std::max(0.4, a.shoulder_z + up * a.reach) * 100.0);
      const Vector3 p_mm(10.0 * std::round(fraction * a.reach * 100.0), 0, start.height_mm);
      start.pose = BestPose(end_model, MakePose(p_mm, R));
      if (start.pose.score > 0) starts.push_back(start);
    }
  }
  std::stable_sort(starts.begin(), starts.end(), [](const ArmStart& x, const ArmStart& y) {
    return x.pose.score > y.pose.score;
  });
  return starts;
}

std::string JointsDeg(const JointVector& q) {
  std::string s = "[";
  for (int i = 0; i < q.size(); ++i) s += (i ? ", " : "") + Num(RadToDeg(q(i)), 2);
  return s + "]";
}

// The model path as the scenario names it: relative to the scenario's folder.
std::string ModelPathFrom(const std::string& model, const std::string& out) {
  const fs::path dir = fs::absolute(fs::path(out)).parent_path();
  std::error_code ec;
  const fs::path rel = fs::relative(fs::absolute(model), dir, ec);
  return ec || rel.empty() ? fs::absolute(model).lexically_normal().string() : rel.string();
}

struct Texts {
  const NewScenarioOptions& o;
  const Arm& a1;
  const Arm& a2;
  const Layout& c;
  const Meeting* meeting = nullptr;  // the handclasp's: where the tips meet
};

std::string RobotEntries(const Texts& t) {
  std::ostringstream s;
  const Arm* arms[2] = {&t.a1, &t.a2};
  for (int k = 0; k < 2; ++k) {
    const Arm& a = *arms[k];
    s << "    - name: r" << k + 1 << "\n"
      << "      model: " << ModelPathFrom(a.path, t.o.out) << "\n";
    if (!a.links.base_link.empty()) s << "      base_link: " << a.links.base_link << "\n";
    if (!a.links.tip_link.empty()) s << "      tip_link: " << a.links.tip_link << "\n";
    s << "      installation: floor\n";
    if (k == 0) {
      s << "      base: {xyz_mm: [0, 0, 0], rpy_deg: [0, 0, 0]}\n"
        << "      initial_joints_deg: " << JointsDeg(t.c.q1) << "\n";
    } else {
      s << "      # the truth; the estimator is told (" << Num(t.c.distance_mm, 0)
        << ", 0, 0) mm, ZYZ (180, 0, 0) deg (calibration / handclasp sections)\n"
        << "      base_from_robot1: {xyz_mm: "
        << List(Vector3(t.c.distance_mm, 0, 0) + Mm(kBaseOffsetMm)) << ", zyz_deg: "
        << List(Mm(kBaseZyzDeg)) << "}\n"
        << "      initial_joints_deg: " << JointsDeg(t.c.q2) << "\n";
    }
  }
  return s.str();
}

std::string CameraAndBoard(const Texts& t, bool small_camera) {
  std::ostringstream s;
  s << "  # The hand camera on r1's flange (true hand-eye X_FC in the flange frame L_N; told: "
       "see below).\n"
    << "  camera:\n    robot: r1\n    hand_eye: " << PoseMap(t.c.X_FC_true) << "\n";
  if (small_camera) {
    s << "    resolution: [640, 480]          # the tracker procedure never looks through it\n"
      << "    fx: 521.44375\n    fy: 520.8625\n    cx: 320.975\n    cy: 252.46875\n";
  } else {
    s << "    resolution: [1024, 768]         # the paper's camera (Zhu et al. 2019, VI.A)\n"
      << "    fx: 834.31\n    fy: 833.38\n    cx: 513.56\n    cy: 403.95\n";
  }
  s << "    msaa: 4\n"
    << "  # A 6 x 6 chessboard of 20 mm squares (25 inner corners, 100 mm across; the paper's\n"
    << "  # 4 x 4 gave the scale to only ~2.5e-4, scenarios/abb_irb2400.yaml) on r2's flange,\n"
    << "  # 40 mm in front of the face.\n"
    << "  board:\n    robot: r2\n    squares: [6, 6]\n    square_mm: 20\n    margin_mm: 10\n"
    << "    thickness_mm: 4\n    mass_kg: 0.3\n    mount: " << PoseMap(t.c.X_FT) << "\n";
  return s.str();
}

std::string Header(const Texts& t, const std::string& title) {
  const Layout& c = t.c;
  const bool flipped = !t.a1.X_LF.linear().isIdentity(1e-9) || !t.a2.X_LF.linear().isIdentity(1e-9);
  std::ostringstream s;
  s << "# " << title << "\n"
    << "# Written by `twinbench new-scenario --robot " << t.o.robot
    << (t.o.second.empty() ? "" : " --second " + t.o.second) << " --procedure " << t.o.procedure
    << "` (bench/scaffold/new_scenario.h).\n"
    << "# Format: bench/io/scenario.h (the cell), bench/io/calibration_config.h (calibration:),\n"
    << "# bench/runs/tracker_run.h (tracker_calibration:), bench/runs/handclasp_run.h (handclasp:).\n"
    << "# `twinbench check FILE` validates it; `twinbench run FILE --out DIR` runs it.\n#\n"
    << "# How the values were derived:\n"
    << "# - reach R: the largest horizontal distance of the flange from the base axis over 4000\n"
    << "#   random joint angles inside the limits: r1 " << Num(t.a1.reach * 1e3, 0) << " mm, r2 "
    << Num(t.a2.reach * 1e3, 0) << " mm (mean " << Num(0.5e3 * (t.a1.reach + t.a2.reach), 0)
    << " mm); shoulder (DH frame L1) " << Num(t.a1.shoulder_z * 1e3, 0) << " mm up.\n"
    << "# - cell: both bases on the floor, facing each other, D = " << Num(c.distance_mm, 0);
  if (t.meeting) {
    const Meeting& m = *t.meeting;
    s << " mm apart (D = 2 g R rounded to\n#   10 mm: the handclasp cube's centre, midway, is g = "
      << Num(m.g, 2) << " of the reach out from each base).\n"
      << "#   g was chosen among " << Num(kMeetFirst, 2) << ", " << Num(kMeetFirst + kMeetStep, 2)
      << ", .., " << Num(kMeetFirst + (kMeetCount - 1) * kMeetStep, 2)
      << " with the run's planner (bench/runs/handclasp_run.h,\n"
      << "#   points: auto) on the nominal models and the told values below, best first: the "
         "largest\n#   cube of which 6 corners are teachable at D and one step of g either side "
         "(here "
      << Num(m.side_m * 1e3, 0) << " mm,\n#   " << Num(m.worst_m * 1e3, 0)
      << " mm at worst beside it); the first whose cell settles without a collision and whose\n"
      << "#   first trial on the twin made a contact at every taught point (the planner knows "
         "the\n#   joint limits, not the links: a folded arm may touch itself).\n";
  }
  if (t.meeting && !c.mid_range) {
    s << "#   Camera and board (not used by the handclasp) meet f = (D - w) / 2R = "
      << Num(c.fraction, 2) << " of the reach\n#   out, w = " << Num(kWorkingDistanceMm, 0)
      << " mm apart, " << Num(c.height_mm, 0) << " mm up; the height was chosen among the "
         "shoulder's\n#   height, 0.25 R and 0.5 R above it: the candidate whose worse arm has "
         "the largest\n#   smallest Jacobian singular value (weighed down within 40 deg of a "
         "joint limit), whose\n#   cell settles without a collision and whose initial joints "
         "teach the cube.\n";
  } else if (!t.meeting) {
    s << " mm apart (D = 2 f R + w rounded to\n#   10 mm: camera and board meet f = "
      << Num(c.fraction, 1) << " of the reach out from each base, w = "
      << Num(kWorkingDistanceMm, 0) << " mm apart, " << Num(c.height_mm, 0) << " mm up).\n"
      << "#   f and the height were chosen among f = 0.5, 0.6, 0.7 and the shoulder's height, "
         "0.25 R\n"
      << "#   and 0.5 R above it: the candidate whose worse arm has the largest smallest "
         "Jacobian\n"
      << "#   singular value (weighed down within 40 deg of a joint limit) and whose cell "
         "settles\n"
      << "#   without a collision.\n";
  }
  if (c.mid_range) {
    s << "# - initial joints: the middle of each joint's range (as the zero pose of\n"
      << "#   scenarios/gan2014_*.yaml): the planner's IK seeds (the encoders once the cell "
         "settled)\n#   and where robot 2 returns between contacts. Camera and board do not "
         "face each other\n#   there; the handclasp does not use them.\n";
  } else {
    s << "# - initial joints: the estimator's IK (calib/kinematics/inverse_kinematics.h, as\n"
      << "#   `twinbench ik`) on the nominal models with the true base and hand-eye: r1's camera "
         "at\n"
      << "#   (" << Num(c.camera_out_mm, 0) << ", 0, " << Num(c.height_mm, 0)
      << ") mm looking along base 1's x at r2, r2's board centre " << Num(kWorkingDistanceMm, 0)
      << " mm further on the optical\n#   axis, its face towards the camera (rolls about the axis "
      << "chosen among 0, 90, 180, 270 deg).\n"
      << "#   r1: smallest Jacobian singular value " << Num(c.sv1, 3) << ", " << Num(c.margin1, 0)
      << " deg from the nearest joint limit; r2: " << Num(c.sv2, 3) << ", " << Num(c.margin2, 0)
      << " deg.\n";
  }
  s << "# - tools: the hand-eye, the board mount, the reflector and the tips are given in the\n"
    << "#   model's flange frame L_N (the DH frame of the last joint). "
    << (flipped ? "On this arm L_N's z points into\n#   the wrist (as KUKA's A6): every tool is "
                  "its z-out value turned 180 deg about x\n#   (x, -y, -z).\n"
                : "On this arm L_N's z points out of\n#   the face.\n")
    << "# - told versus true (the truth is never read for a told value): base-to-base off by\n"
    << "#   (3.2, -2.6, 0.8) mm and ZYZ (-0.3, 0.2, -0.1) deg; the hand-eye off by (2.1, 1.6, 1.7) mm\n"
    << "#   and RPY (0.8, -0.6, 1.1) deg (the paper scenario's amounts); the board, the reflector\n"
    << "#   and the tips by drawing (the reflector as built ~1 mm off); kinematics: the nominal\n"
    << "#   model, the truth drawn by the geometry_errors effect below.\n";
  return s.str();
}

// The truth's geometry errors and encoder noise of every procedure's file: Table 3's
// magnitudes (sigma 2 mm and 0.25 deg per DH parameter) and paper_reinovo.yaml's noise.
constexpr const char* kTruthEffects =
    "  effects:\n    - type: geometry_errors\n      sigma_length_mm: 2.0\n"
    "      sigma_angle_deg: 0.25\n    - type: encoder_noise\n      sigma_deg: 0.0005\n";

// Whether one of the joints that set the arm's posture (1-3) turns more than a full turn
// (a UR's +-360 deg): the middle of its range is then no posture. (A +-180 deg base joint
// turns exactly one turn and keeps its middle.)
bool PostureJointsTurnFully(const KinematicModel& m) {
  for (int i = 0; i < 3; ++i) {
    // 1 deg: a URDF rounds +-pi to +-3.1416
    if (m.links[i].limits.upper - m.links[i].limits.lower > 2.0 * kPi + DegToRad(1.0)) return true;
  }
  return false;
}

// The planner's IK start (calibration_config.h, planning.ik_seed): the start pose for arms
// whose posture joints turn fully, where the mid-range default gives every axis its own branch
// and whole-turn wraps (a UR5e lost 66-72 of 100 poses to self-collisions in the moves); the
// default (no line) for the others.
std::string IkSeedLine(const Texts& t) {
  if (!PostureJointsTurnFully(t.a1.model) && !PostureJointsTurnFully(t.a2.model)) return "";
  return "      # joints 1-3 turn more than a turn: the middle of their range is no posture, so each\n"
         "      # axis's IK starts from the start pose above (pose_planner.h, active_ik_seed)\n"
         "      ik_seed: start_pose\n";
}

std::string OpticalAxisText(const Texts& t) {
  const Layout& c = t.c;
  const Transform told_he = t.a1.X_LF * MakePose(Mm(kToldHandEyeMm), Matrix3::Identity());
  std::ostringstream s;
  s << Header(t, "Optical-axis self-calibration (Zhu et al. 2019) of two arms: " +
                     t.a1.model.name + " (r1, camera) and " + t.a2.model.name + " (r2, board).")
    << "scenario:\n  format: " << kScenarioFormat << "   # the scenario format version\n"
    << "  name: " << fs::path(t.o.out).stem().string() << "\n"
    << "  seed: 2019                        # truth and estimator seeds (`run --trial t`: + t)\n"
    << "  robots:\n" << RobotEntries(t) << CameraAndBoard(t, false)
    << "  # Joint speed of the motion program: the figures do not depend on it (paper_reinovo.yaml).\n"
    << "  physics: {max_joint_speed_deg_s: 180}\n"
    << "  intrinsics_target:                # swapped onto the board's bracket for Zhang's method\n"
    << "    squares: [14, 10]\n    square_mm: 20\n    margin_mm: 10\n    thickness_mm: 5\n"
    << "    mass_kg: 0.6\n"
    << "  # The truth's errors: Table 3's magnitudes (sigma 2 mm and 0.25 deg per DH parameter)\n"
    << "  # and the noise of paper_reinovo.yaml.\n"
    << kTruthEffects
    << "    - type: image_noise\n      sigma_levels: 1.0\n"
    << "  # What the estimator is told, and the procedure's options.\n"
    << "  calibration:\n    robots: [r2, r1]\n"
    << "    rough_base_from_robot1: {xyz_mm: [" << Num(c.distance_mm, 0)
    << ", 0, 0], zyz_deg: [180, 0, 0]}   # the layout as drawn\n"
    << "    rough_hand_eye: " << PoseMap(told_he) << "   # by drawing\n"
    << "    board_mount: " << PoseMap(c.X_FT) << "   # by drawing (made to it)\n"
    << "    board_squares: [6, 6]\n    board_square_mm: 20\n"
    << "    intrinsics_target: {squares: [14, 10], square_mm: 20}\n    intrinsics_views: 40\n"
    << "    # Planning (section IV, eq. 50): the distances belong to the camera and the board\n"
    << "    # (300..600 mm, axes of 10 positions 30 mm apart: 270 mm, as abb_irb2400.yaml); the\n"
    << "    # camera's search box (+-150 mm) is centred on r1's start pose, which scales with R.\n"
    << "    planning:\n      axes: 10\n      positions_per_axis: 10\n      swarm_size: 10\n"
    << "      iterations: 100\n      runs: 5\n      distance_step_mm: 30\n"
    << "      planning_max_distance_mm: 600\n      min_distance_mm: 300\n"
    << "      max_distance_mm: 600\n      min_joint_limit_distance_deg: 10\n"
    << "      min_singular_value: 0.1\n      max_visibility_angle_deg: 30\n"
    << "      camera_reach_mm: " << Num(c.camera_out_mm, 0) << "\n"
    << "      camera_height_mm: " << Num(c.height_mm, 0) << "\n      seed: 1\n"
    << IkSeedLine(t)
    << "    servo: {tolerance_px: 0.1, max_iterations: 10, gain: 1.0, encoder_readings: 16}\n"
    << "    calibration_axes: 6\n    scoring: {configurations: 200, seed: 1}\n"
    << "  # The CI verdict (bench/report/acceptance.h): issue 13's targets for an added arm, over\n"
    << "  # the region the calibration poses covered; `twinbench run` exits 3 when one is missed.\n"
    << "  acceptance:\n";
  for (const char* r : {"r2", "r1"}) {
    s << "    - {figure: robots." << r << ".misaligned_error_mm.validation.after, max: 0.05}\n"
      << "    - {figure: robots." << r
      << ".truth_position_error_mm_covered_region.rigid.after.rms, max: 0.3}\n"
      << "    - {figure: robots." << r
      << ".truth_position_error_mm_covered_region.similarity.after.rms, max: 0.1}\n";
  }
  return s.str();
}

// The encoders' noise as the estimator is told it (tracker_run.h, encoder_sigma_deg): the
// datasheet's figure, a little above the 0.0005 deg kTruthEffects injects. Without it the
// diagnosis's noise floor is the tracker's alone, while the encoders move the reflector about as
// much again: a clean Reinovo arm read `unexplained` in 12 of 20 trials.
constexpr const char* kToldEncoderNoise =
    "    encoder_sigma_deg: 0.0006       # the encoders' datasheet noise (told; the diagnosis's\n"
    "                                    # noise floor carries it through the model)\n";

// The one-robot tracker cell's cap on configurations tried (tracker_run.h, max_attempts; the
// default is 3 x poses). A random configuration of an arm whose posture joints turn more than a
// turn (a UR's +-360 deg) often sweeps the arm through itself on the way: a UR5e measured 36 of
// 100 poses in 300 attempts (250 moves collided), so 100 poses need about 830. The cap costs
// nothing on an arm that finds its poses sooner.
std::string SingleTrackerAttempts(const KinematicModel& m) {
  if (PostureJointsTurnFully(m)) {
    return "    max_attempts: 1500              # joints 1-3 turn more than a turn: many random\n"
           "                                    # configurations' moves collide with the arm itself\n";
  }
  return "    max_attempts: 600               # some random configurations' moves collide\n";
}

std::string TrackerText(const Texts& t) {
  const Layout& c = t.c;
  const double behind_mm = c.distance_mm + 1e3 * std::max(2.0, 2.0 * t.a2.reach);
  const Vector3 told = t.a2.X_LF * Mm(kToldReflectorMm);
  const Vector3 truth = t.a2.X_LF * Mm(kTrueReflectorMm);
  std::ostringstream s;
  s << Header(t, "Laser-tracker calibration of " + t.a2.model.name +
                     " (r2) on the twin (bench/runs/tracker_run.h).")
    << "# The optical-axis cell of the two arms (--second given; without it the cell is one arm\n"
    << "# alone): r1, the camera and the board take no part; the board stays on r2 as its\n"
    << "# payload.\n"
    << "scenario:\n  format: " << kScenarioFormat << "   # the scenario format version\n"
    << "  name: " << fs::path(t.o.out).stem().string() << "\n"
    << "  seeds: {truth: 2019, estimator: 2019}\n"
    << "  robots:\n" << RobotEntries(t) << CameraAndBoard(t, true)
    << kTruthEffects
    << "  # The tracker (truth): behind r2, max(2 m, 2 R) beyond its base, facing back at it.\n"
    << "  tracker:\n    robot: r2\n"
    << "    pose: {xyz_mm: [" << Num(behind_mm, 0) << ", 400, " << Num(c.height_mm, 0)
    << "], rpy_deg: [0.5, -0.3, 172]}\n"
    << "    reflector_mm: " << List(truth) << "   # as built (told: the drawing, below)\n"
    << "    sigma_mm: 0.01\n    max_range_m: 20\n"
    << "  tracker_calibration:\n    robot: r2\n"
    << "    told_reflector_mm: " << List(told) << "   # by drawing: off the truth by "
    << "(0.6, 0.8, 0.9) mm in F'\n"
    << "    poses: 100\n"
    << "    max_attempts: 600               # random configurations collide with the board often\n"
    << "    holdout: 0.2\n"
    << kToldEncoderNoise
    << "    payload: {mass_kg: 0.3, xyz_mm: " << List(c.X_FT.translation() * 1e3)
    << "}   # the board and its bracket\n"
    << "  acceptance:                       # as scenarios/tracker_reinovo.yaml\n"
    << "    - {figure: truth_position_error_mm.rigid.after.rms, max: 0.03}\n";
  return s.str();
}

// The one-robot tracker cell (no --second): r1 alone, no camera, board or second robot.
std::string SingleTrackerText(const NewScenarioOptions& o, const Arm& a, const ArmStart& st) {
  const double behind_mm = 1e3 * std::max(2.0, 2.0 * a.reach);
  const Vector3 told = a.X_LF * Mm(kToldReflectorMm);
  const Vector3 truth = a.X_LF * Mm(kTrueReflectorMm);
  const bool flipped = !a.X_LF.linear().isIdentity(1e-9);
  std::ostringstream s;
  s << "# Laser-tracker calibration of " << a.model.name << " (r1) alone on the twin "
    << "(bench/runs/tracker_run.h):\n# a one-robot cell, without camera, board or second robot.\n"
    << "# Written by `twinbench new-scenario --robot " << o.robot << " --procedure tracker` "
    << "(bench/scaffold/new_scenario.h).\n"
    << "# Format: bench/io/scenario.h (the cell), bench/runs/tracker_run.h "
       "(tracker_calibration:).\n"
    << "# `twinbench check FILE` validates it; `twinbench run FILE --out DIR` runs it.\n#\n"
    << "# How the values were derived:\n"
    << "# - reach R: the largest horizontal distance of the flange from the base axis over 4000\n"
    << "#   random joint angles inside the limits: " << Num(a.reach * 1e3, 0)
    << " mm; shoulder (DH frame L1) " << Num(a.shoulder_z * 1e3, 0) << " mm up.\n"
    << "# - initial joints: the estimator's IK (calib/kinematics/inverse_kinematics.h, as\n"
    << "#   `twinbench ik`) on the nominal model: the flange face at ("
    << Num(10.0 * std::round(st.fraction * a.reach * 100.0), 0) << ", 0, "
    << Num(st.height_mm, 0) << ") mm (" << Num(st.fraction, 1) << " R out),\n"
    << "#   pointing out along the base's x; smallest Jacobian singular value "
    << Num(st.pose.sv, 3) << ",\n#   " << Num(st.pose.margin, 0)
    << " deg from the nearest joint limit.\n"
    << "# - the reflector is given in the model's flange frame L_N (the DH frame of the last "
       "joint)"
    << (flipped ? ";\n#   on this arm L_N's z points into the wrist: the z-out value turned 180 "
                  "deg about x.\n"
                : ".\n")
    << "# - told versus true (the truth is never read for a told value): the reflector by "
       "drawing,\n#   as built ~1 mm off; kinematics: the nominal model, the truth drawn by the\n"
    << "#   geometry_errors effect below.\n"
    << "scenario:\n  format: " << kScenarioFormat << "   # the scenario format version\n"
    << "  name: " << fs::path(o.out).stem().string() << "\n"
    << "  seeds: {truth: 2019, estimator: 2019}\n"
    << "  robots:                           # one robot: no camera, board or second robot\n"
    << "    - name: r1\n      model: " << ModelPathFrom(a.path, o.out) << "\n";
  if (!a.links.base_link.empty()) s << "      base_link: " << a.links.base_link << "\n";
  if (!a.links.tip_link.empty()) s << "      tip_link: " << a.links.tip_link << "\n";
  s << "      installation: floor\n"
    << "      base: {xyz_mm: [0, 0, 0], rpy_deg: [0, 0, 0]}\n"
    << "      initial_joints_deg: " << JointsDeg(st.pose.q) << "\n"
    << kTruthEffects
    << "  # The tracker (truth): max(2 m, 2 R) behind the base, facing it.\n"
    << "  tracker:\n    robot: r1\n"
    << "    pose: {xyz_mm: [" << Num(-behind_mm, 0) << ", -400, " << Num(st.height_mm, 0)
    << "], rpy_deg: [0.5, -0.3, -8]}\n"
    << "    reflector_mm: " << List(truth) << "   # as built (told: the drawing, below)\n"
    << "    sigma_mm: 0.01\n    max_range_m: 20\n"
    << "  tracker_calibration:\n    robot: r1\n"
    << "    told_reflector_mm: " << List(told) << "   # by drawing: off the truth by "
    << "(0.6, 0.8, 0.9) mm in F'\n"
    << "    poses: 100\n" << SingleTrackerAttempts(a.model) << "    holdout: 0.2\n"
    << kToldEncoderNoise
    << "  acceptance:                       # as scenarios/tracker_reinovo.yaml\n"
    << "    - {figure: truth_position_error_mm.rigid.after.rms, max: 0.03}\n";
  return s.str();
}

std::string HandclaspText(const Texts& t) {
  const Layout& c = t.c;
  const double tip_mm = kHandclaspTipMm;
  const Transform tip1 = HandclaspTip(t.a1, tip_mm);
  const Transform tip2 = HandclaspTip(t.a2, tip_mm);
  std::ostringstream s;
  s << Header(t, "Handclasp base-frame calibration (Gan et al. 2014) of " + t.a1.model.name +
                     " (r1) and " + t.a2.model.name + " (r2).")
    << "# Geometry errors: a factory-calibrated arm's (sigma 0.5 mm and 0.05 deg per DH\n"
    << "# parameter, as scenarios/gan2014_*.yaml); the operator aligns the tips to 0.5 mm.\n"
    << "scenario:\n  format: " << kScenarioFormat << "   # the scenario format version\n"
    << "  name: " << fs::path(t.o.out).stem().string() << "\n  seed: " << kHandclaspSeed
    << "\n"
    << "  robots:\n" << RobotEntries(t) << CameraAndBoard(t, false)
    << "  # Measuring tips " << Num(tip_mm, 0) << " mm out of each flange (as "
       "scenarios/gan2014_*.yaml), beyond the\n  # camera and the board; D puts the handclasp "
       "cube where both arms reach it (header).\n"
    << "  tips:\n"
    << "    r1: " << PoseMap(tip1).substr(0, PoseMap(tip1).size() - 1) << ", length_mm: "
    << Num(tip_mm - 20, 0) << ", radius_mm: 4}\n"
    << "    r2: " << PoseMap(tip2).substr(0, PoseMap(tip2).size() - 1) << ", length_mm: "
    << Num(tip_mm - 20, 0) << ", radius_mm: 4}\n"
    << "  handclasp:\n"
    << "    rough_base_from_robot1: {xyz_mm: [" << Num(c.distance_mm, 0)
    << ", 0, 0], zyz_deg: [180, 0, 0]}   # the layout as drawn\n"
    << "    tips:                           # by drawing (the tips are made to it)\n"
    << "      r1: " << PoseMap(tip1) << "\n      r2: " << PoseMap(tip2) << "\n"
    << "    points: auto\n    operator_error_mm: 0.5\n    constraint: auto\n    trials: 3\n"
    << "  effects:\n    - type: geometry_errors\n      sigma_length_mm: 0.5\n"
    << "      sigma_angle_deg: 0.05\n";
  return s.str();
}

// What `twinbench check` checks (bench/runs/calibration_run.cc, CheckScenario) on the text
// before the cell is built: the scenario as parsed.
Scenario ParseScenarioText(const std::string& text, const std::string& out) {
  const std::string dir = fs::absolute(fs::path(out)).parent_path().string();
  const Scenario sc = ParseScenario(text, out, dir);
  if (IsPresent(sc.calibration)) ParseCalibrationConfig(sc);
  if (IsPresent(sc.handclasp)) ParseHandclaspConfig(sc);
  if (IsPresent(sc.tracker_calibration)) ValidateTrackerScenario(sc);
  ParseAcceptance(sc);
  InstallMujocoErrorHandlers();
  return sc;
}

// What `twinbench check` checks, on the text.
void CheckScenarioText(const std::string& text, const std::string& out) {
  const Scenario sc = ParseScenarioText(text, out);
  const TwinCell cell(sc.twin, sc.path);  // the cell settles at its initial pose
}

// The handclasp scenario: the best kMeetsTried meeting points of the tips (HandclaspMeetings),
// each with the arms at mid-range, else (where that cell cannot start) the optical-axis start
// poses; the first file whose initial joints teach the cube as the run will
// (TeachHandclaspPoints on the file's nominal models and told values), whose cell settles
// without a collision (the check) and whose first trial on the twin (RunHandclaspStage, as
// `twinbench run`) made a contact at every taught point.
std::string HandclaspScenarioText(const NewScenarioOptions& o, const Arm& a1, const Arm& a2) {
  const std::vector<Meeting> meetings = HandclaspMeetings(a1, a2, kHandclaspTipMm);
  if (meetings.empty()) {
    throw InputError("--robot", "no handclasp cell found: with " + Num(kHandclaspTipMm, 0) +
                                    " mm tips the planner taught 6 corners of no cube for "
                                    "bases 2 g R apart, g = " + Num(kMeetFirst, 2) + ".." +
                                    Num(kMeetFirst + (kMeetCount - 1) * kMeetStep, 2));
  }
  const double reach = 0.5 * (a1.reach + a2.reach);
  const double shoulder = 0.5 * (a1.shoulder_z + a2.shoulder_z);
  std::string last_error;
  // Where a cell failed: at its start (no cube taught from its initial joints, or the cell
  // does not settle without a collision) or in its first trial on the twin.
  enum class Failed { kNothing, kStart, kTrial };
  // Writes the file to *text unless its initial joints teach no cube (on the nominal models,
  // as the test does), its cell does not settle without a collision (the check) or its first
  // trial on the twin left a taught point without a contact (the planner knows the joint
  // limits, not the links: a folded arm may touch itself).
  const auto attempt = [&](const Layout& c, const Meeting& m, std::string* text) -> Failed {
    *text = HandclaspText(Texts{o, a1, a2, c, &m});
    const std::string at = "D = " + Num(m.distance_mm, 0) + " mm: ";
    try {
      const Scenario sc = ParseScenarioText(*text, o.out);
      const std::array<KinematicModel, 2> nominal = {sc.twin.robots[0].model,
                                                     sc.twin.robots[1].model};
      const TaughtPoints taught = TeachHandclaspPoints(
          ParseHandclaspConfig(sc), nominal,
          {sc.twin.robots[0].q_initial, sc.twin.robots[1].q_initial},
          HandclaspTeachOptions(sc, false));
      if (!taught.ok) {
        last_error = at + taught.reason;
        return Failed::kStart;
      }
      TwinCell cell(sc.twin, sc.path);  // the cell settles at its initial pose
      std::ostringstream progress;
      const HandclaspStageResult trial = RunHandclaspStage(cell, sc, nominal, progress);
      if (trial.ok() && trial.procedure.skipped.empty()) return Failed::kNothing;
      last_error = at + "first trial: " +
                   (trial.ok() ? trial.procedure.skipped.front() : trial.reason);
      return Failed::kTrial;
    } catch (const InputError& e) {
      last_error = at + e.what();  // a collision at the start pose
      return Failed::kStart;
    }
  };
  for (std::size_t i = 0; i < meetings.size() && i < static_cast<std::size_t>(kMeetsTried);
       ++i) {
    const Meeting& m = meetings[i];
    const double fraction = (m.distance_mm - kWorkingDistanceMm) / (2e3 * reach);
    // The arms at mid-range, the seeds the meeting point was found with; where the cell cannot
    // start from there, the optical-axis start poses at this D.
    Layout mid = CellFrames(a1, a2, fraction, m.distance_mm, std::max(0.4, shoulder));
    mid.q1 = MidRange(a1.model);
    mid.q2 = MidRange(a2.model);
    mid.mid_range = true;
    std::string text;
    const Failed failed = attempt(mid, m, &text);
    if (failed == Failed::kNothing) return text;
    if (failed == Failed::kTrial) continue;
    std::vector<Layout> cells;
    AddCellsAt(a1, a2, fraction, m.distance_mm, &cells);
    SortByScore(&cells);
    for (const Layout& c : cells) {
      const Failed f = attempt(c, m, &text);
      if (f == Failed::kNothing) return text;
      if (f == Failed::kTrial) break;
    }
  }
  throw InputError("--robot", "no handclasp cell of the best " + std::to_string(kMeetsTried) +
                                  " meeting points taught its cube and made every contact on "
                                  "the twin; the last one's: " + last_error);
}

// A lone arm's tracker scenario: the first candidate start whose cell passes the check.
std::string SingleTrackerScenario(const NewScenarioOptions& o, const Arm& a) {
  const std::vector<ArmStart> starts = CandidateStarts(a);
  if (starts.empty()) {
    throw InputError("--robot", "no start pose found: IK put the flange face out along the "
                                "base's x at none of the candidate points (0.5..0.7 of the "
                                "reach out, 15 deg or more from every joint limit)");
  }
  std::string last_error;
  for (const ArmStart& st : starts) {
    const std::string text = SingleTrackerText(o, a, st);
    try {
      CheckScenarioText(text, o.out);
      return text;
    } catch (const InputError& e) {
      last_error = e.what();  // a collision at the start pose: the next candidate
    }
  }
  throw InputError("--robot", "no candidate start passed the check; the last one's: " +
                                  last_error);
}

}  // namespace

std::string NewScenarioText(const NewScenarioOptions& o) {
  if (o.procedure != "optical-axis" && o.procedure != "tracker" && o.procedure != "handclasp") {
    throw InputError("--procedure", "expected optical-axis, tracker or handclasp, got '" +
                                        o.procedure + "'");
  }
  const Arm a1 = LoadArm(o.robot, o.links, "--robot");
  // The tracker needs one robot: without --second the cell is the arm alone.
  if (o.procedure == "tracker" && o.second.empty()) return SingleTrackerScenario(o, a1);
  const Arm a2 = o.second.empty() ? a1 : LoadArm(o.second, o.second_links, "--second");
  if (o.procedure == "handclasp") return HandclaspScenarioText(o, a1, a2);
  const std::vector<Layout> cells = CandidateCells(a1, a2);
  if (cells.empty()) {
    throw InputError("--robot", "no cell found: IK put camera and board face to face at none of "
                                "the candidate meeting points (0.5..0.7 of the reach out, 15 deg "
                                "or more from every joint limit)");
  }
  std::string last_error;
  for (std::size_t k = 0; k < cells.size(); ++k) {
    const Texts t{o, a1, a2, cells[k]};
    const std::string text = o.procedure == "tracker" ? TrackerText(t) : OpticalAxisText(t);
    try {
      CheckScenarioText(text, o.out);
      return text;
    } catch (const InputError& e) {
      last_error = e.what();  // a collision at the start pose: the next candidate
    }
  }
  throw InputError("--robot", "no candidate cell passed the check; the best one's: " + last_error);
}

int RunNewScenario(const NewScenarioOptions& o) {
  ValidateOutputFile(o.out, "--out");  // refuses any existing file, a folder, a missing folder
  const std::string text = NewScenarioText(o);
  // Atomic and never replacing: a complete temporary file beside --out, hard-linked to --out
  // (link fails where --out appeared meanwhile), then the temporary name removed.
  const fs::path out = fs::absolute(fs::path(o.out));
  std::string tmp = (out.parent_path() / ("." + out.filename().string() + ".XXXXXX")).string();
  const int fd = mkstemp(tmp.data());
  if (fd < 0) throw InputError("--out", "cannot create a file beside '" + o.out + "': " +
                                            std::strerror(errno));
  const bool written = write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  const bool closed = close(fd) == 0;
  if (!written || !closed || link(tmp.c_str(), out.c_str()) != 0) {
    const std::string why = !written || !closed ? "cannot write" : std::strerror(errno);
    unlink(tmp.c_str());
    throw InputError("--out", "'" + o.out + "': " + why + "; expected a new file");
  }
  unlink(tmp.c_str());
  std::printf("wrote %s (%s; `twinbench check %s` validates it)\n", o.out.c_str(),
              o.procedure.c_str(), o.out.c_str());
  return 0;
}

}  // namespace twin
