#include "calib/procedures/handclasp_procedure.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <ostream>
#include <sstream>

#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"

namespace twin {
namespace {

constexpr int kMinContacts = 4;  // paper section 2.2: four handclasp contacts determine X_B1B2

std::string Mm(const Vector3& p) {
  std::ostringstream os;
  os.precision(1);
  os << std::fixed << "(" << 1e3 * p.x() << ", " << 1e3 * p.y() << ", " << 1e3 * p.z() << ") mm";
  return os.str();
}

Transform MakePose(const Matrix3& R, const Vector3& p) {
  Transform X = Transform::Identity();
  X.linear() = R;
  X.translation() = p;
  return X;
}

// A point on robot `model`'s joint-2 axis (origin of DH frame L1 at q = 0), in its base frame:
// the "shoulder" the planner points robot 1's tip at.
Vector3 Shoulder(const KinematicModel& model) {
  return ForwardKinematics(model, ZeroJoints(model)).X_BL[1].translation();
}

// A unit vector perpendicular to u, preferring the one in the horizontal plane of B1.
Vector3 Perpendicular(const Vector3& u) {
  Vector3 v = Vector3::UnitZ().cross(u);
  if (v.norm() < 1e-6) v = Vector3::UnitX().cross(u);
  return v.normalized();
}

struct Teach {
  bool ok = false;
  std::string reason;
  JointVector q1;
};

// IK for a tip pose with position p and z axis z, trying `rolls` roll angles about z.
IkResult TipIk(const KinematicModel& model, const Vector3& p, const Matrix3& R_z_frame,
               const JointVector& seed, const TeachOptions& o) {
  IkOptions ik;
  ik.random_restarts = o.ik_restarts;
  ik.seed = o.seed;
  IkResult last;
  for (int r = 0; r < o.rolls; ++r) {
    const double roll = 2.0 * kPi * r / o.rolls;
    const Matrix3 R = R_z_frame * Eigen::AngleAxisd(roll, Vector3::UnitZ()).toRotationMatrix();
    last = SolveIk(model, MakePose(R, p), seed, ik);
    if (last.status == IkStatus::kSuccess) return last;
  }
  return last;
}

// A rotation whose z axis is u.
Matrix3 FrameWithZ(const Vector3& u) {
  Matrix3 R;
  const Vector3 x = Perpendicular(u);
  R.col(0) = x;
  R.col(1) = u.cross(x);
  R.col(2) = u;
  return R;
}

// Robot 1's tip direction for orientation `k` of a point: towards robot 2's shoulder (k = 0),
// else tilted by o.tilt_deg about an axis perpendicular to it, the axes spread evenly.
Vector3 TipDirection(const std::array<KinematicModel, 2>& m, const Transform& X_B1B2,
                     const Vector3& p_B1, int k, const TeachOptions& o) {
  const Vector3 u = (X_B1B2 * Shoulder(m[1]) - p_B1).normalized();
  if (k == 0) return u;
  const Vector3 a = Perpendicular(u);
  const double spin = 2.0 * kPi * (k - 1) / std::max(1, o.orientations_per_point - 1);
  const Vector3 axis = Eigen::AngleAxisd(spin, u) * a;
  return Eigen::AngleAxisd(DegToRad(o.tilt_deg), axis) * u;
}

Teach TeachOne(const std::array<KinematicModel, 2>& m, const Transform& X_B1B2,
               const Vector3& p_B1, const Vector3& u, const std::array<JointVector, 2>& seed,
               const TeachOptions& o) {
  Teach t;
  if (p_B1.z() < o.min_height_m) {
    t.reason = "lower than min_height_m";
    return t;
  }
  const IkResult r1 = TipIk(m[0], p_B1, FrameWithZ(u), seed[0], o);
  if (r1.status != IkStatus::kSuccess) {
    t.reason = std::string("robot 1 cannot reach it (IK ") + ToString(r1.status) + ")";
    return t;
  }
  // Robot 2's facing tip at the point and at its stand-off (section 3: robot 2 approaches).
  const Transform X_B2B1 = X_B1B2.inverse();
  const Matrix3 R2 = X_B2B1.linear() * FrameWithZ(-u);
  for (const double back : {o.standoff_m, 0.0}) {
    const IkResult r2 = TipIk(m[1], X_B2B1 * (p_B1 + back * u), R2, seed[1], o);
    if (r2.status != IkStatus::kSuccess) {
      t.reason = std::string("robot 2 cannot reach it") + (back > 0 ? " (stand-off)" : "") +
                 " (IK " + ToString(r2.status) + ")";
      return t;
    }
  }
  t.ok = true;
  t.q1 = r1.q;
  return t;
}

// Throws PreconditionError naming the first taught joint vector that is not finite: they are
// IK solutions of TeachPoints or PlanTaughtPoints, never a user's numbers.
void RequireFiniteTaughtAngles(const std::vector<JointVector>& taught_q1) {
  for (size_t i = 0; i < taught_q1.size(); ++i) {
    TWIN_REQUIRE(taught_q1[i].allFinite(),
                 "taught_q1[" + std::to_string(i) + "]: joint angles must be finite");
  }
}

// Writes "handclasp: line" to log when there is one.
void Note(std::ostream* log, const std::string& line) {
  if (log) *log << "handclasp: " << line << "\n";
}

// What the contact loop works with: the cell, the pendant tip models, the options, the log
// (may be null) and robot 2's start pose.
struct ContactSession {
  Cell& cell;
  const std::array<KinematicModel, 2>& pendant_tip_models;
  const HandclaspOptions& options;
  std::ostream* log;
  JointVector q2_home;  // robot 2's encoders before the first contact [rad]
};

// Robot 2 backs off along its tip axis (pendant IK, a linear tool move on a pendant), then
// returns to where it started.
void RetractRobot2(const ContactSession& s, const std::string& what) {
  const JointVector q2 = s.cell.ReadEncoders(1);
  if (s.options.retract_m > 0) {
    const Transform X = EndPose(s.pendant_tip_models[1], q2) *
                        Eigen::Translation3d(0, 0, -s.options.retract_m);
    const IkResult ik = SolveIk(s.pendant_tip_models[1], X, q2, s.options.ik);
    if (ik.status == IkStatus::kSuccess) {
      const MoveResult back = s.cell.MoveTo(1, ik.q);
      if (back.status != MoveStatus::kSettled) {
        Note(s.log, what + ": backing off: " + ToString(back.status) + ": " + back.reason);
      }
    }
  }
  const MoveResult home = s.cell.MoveTo(1, s.q2_home);
  if (home.status != MoveStatus::kSettled) {
    Note(s.log, what + ": robot 2 back to its start pose: " + ToString(home.status) + ": " +
                    home.reason);
  }
}

// For each taught point: robot 1 there, robot 2 jogged onto its tip, both encoders read and
// the pendant tip positions recorded, robot 2 retracted; failed moves go to result->skipped.
void RegisterContacts(const ContactSession& s, const std::vector<JointVector>& taught_q1,
                      HandclaspResult* result) {
  for (size_t i = 0; i < taught_q1.size(); ++i) {
    const std::string what = "point " + std::to_string(i);
    const MoveResult move = s.cell.MoveTo(0, taught_q1[i]);
    if (move.status != MoveStatus::kSettled) {
      result->skipped.push_back(what + ": robot 1 move " + ToString(move.status) + ": " +
                                move.reason);
      Note(s.log, "skipped " + result->skipped.back());
      continue;
    }
    const MoveResult jog = s.cell.JogTipToContact(1);
    if (jog.status != MoveStatus::kSettled) {
      result->skipped.push_back(what + ": contact " + ToString(jog.status) + ": " + jog.reason);
      Note(s.log, "skipped " + result->skipped.back());
      RetractRobot2(s, what);
      continue;
    }
    HandclaspContact c;
    c.point = static_cast<int>(i);
    c.q1 = s.cell.ReadEncoders(0);
    c.q2 = s.cell.ReadEncoders(1);
    c.p_B1 = EndPose(s.pendant_tip_models[0], c.q1).translation();
    c.p_B2 = EndPose(s.pendant_tip_models[1], c.q2).translation();
    result->contacts.push_back(c);
    Note(s.log, what + ": contact at " + Mm(c.p_B1) + " in B1, " + Mm(c.p_B2) + " in B2");
    RetractRobot2(s, what);
  }
}

// False, with status kTooFewContacts and the skipped points in the reason, when fewer than
// kMinContacts of the `taught` points gave a contact.
bool HasEnoughContacts(size_t taught, HandclaspResult* result) {
  if (result->contacts.size() < static_cast<size_t>(kMinContacts)) {
    result->status = HandclaspResult::Status::kTooFewContacts;
    result->reason = "only " + std::to_string(result->contacts.size()) + " of " +
                     std::to_string(taught) + " handclasp contacts succeeded, need " +
                     std::to_string(kMinContacts);
    for (const std::string& s : result->skipped) result->reason += "; " + s;
    return false;
  }
  return true;
}

// CalibrateBaseFrame on the contacts' point pairs; false, with status kCalibrationFailed, when
// it did not succeed. Its warnings are logged.
bool CalibrateFromContacts(const HandclaspOptions& options, std::ostream* log,
                           HandclaspResult* result) {
  std::vector<Vector3> p_B1, p_B2;
  for (const HandclaspContact& c : result->contacts) {
    p_B1.push_back(c.p_B1);
    p_B2.push_back(c.p_B2);
  }
  result->calibration = CalibrateBaseFrame(p_B1, p_B2, options.constraint, options.base);
  for (const std::string& w : result->calibration.warnings) Note(log, "warning: " + w);
  if (!result->calibration.ok()) {
    result->status = HandclaspResult::Status::kCalibrationFailed;
    result->reason = std::string("base calibration ") + ToString(result->calibration.status) +
                     ": " + result->calibration.reason;
    return false;
  }
  return true;
}

// RefineBaseAndTips from the contacts' flange poses, started at the general X_B1B2; a failure
// becomes a warning of the calibration.
void IdentifyTips(const std::array<KinematicModel, 2>& pendant_tip_models,
                  const TipRefinementOptions& tip_options, std::ostream* log,
                  HandclaspResult* result) {
  // Flange poses from the pendant models (tip tool removed) and the tips on the flanges.
  std::vector<Transform> X_B1F1, X_B2F2;
  std::array<KinematicModel, 2> flange = pendant_tip_models;
  for (KinematicModel& f : flange) f.X_LtE = Transform::Identity();
  for (const HandclaspContact& c : result->contacts) {
    X_B1F1.push_back(EndPose(flange[0], c.q1));
    X_B2F2.push_back(EndPose(flange[1], c.q2));
  }
  const Transform& X_FTip1 = pendant_tip_models[0].X_LtE;
  result->tips = RefineBaseAndTips(X_B1F1, X_B2F2, X_FTip1.translation(),
                                   pendant_tip_models[1].X_LtE.translation(),
                                   X_FTip1.linear().col(2), result->calibration.X_B1B2_general,
                                   tip_options);
  if (result->tips.ok) {
    Note(log, "tips identified: robot 1 " + Mm(result->tips.dt1_F1) + ", robot 2 " +
                  Mm(result->tips.dt2_F2) + " on the flanges; RMS contact mismatch " +
                  std::to_string(1e3 * result->tips.rms_residual_before_m) + " -> " +
                  std::to_string(1e3 * result->tips.rms_residual_m) + " mm");
  } else {
    result->calibration.warnings.push_back("tip identification: " + result->tips.reason);
    Note(log, "warning: tip identification: " + result->tips.reason);
  }
}

}  // namespace

KinematicModel WithTipTool(const KinematicModel& flange_model, const Transform& X_FTip) {
  KinematicModel m = flange_model;
  m.tool().dh = DhParameters{};  // L7 = L6 = F
  m.X_LtE = X_FTip;
  return m;
}

Matrix3 FacingTipRotation(const Matrix3& R_A_TipOther, double roll) {
  return R_A_TipOther * Eigen::AngleAxisd(kPi, Vector3::UnitX()).toRotationMatrix() *
         Eigen::AngleAxisd(roll, Vector3::UnitZ()).toRotationMatrix();
}

void TeachOptions::Validate() const {
  // No user sets these (the handclasp run sets the seed and the orientations): a bad value is
  // our bug.
  const auto fail = [](const std::string& field, const std::string& msg) {
    FailPrecondition("valid TeachOptions", "TeachOptions." + field + " " + msg, __FILE__,
                     __LINE__);
  };
  if (cube_sides_m.empty()) fail("cube_sides_m", "must list at least one side");
  for (double s : cube_sides_m) {
    if (!(std::isfinite(s) && s > 0)) fail("cube_sides_m", "sides must be > 0, got " + std::to_string(s));
  }
  if (min_points < kMinContacts || min_points > 8) {
    fail("min_points", "must be in 4..8, got " + std::to_string(min_points));
  }
  if (!std::isfinite(min_height_m)) fail("min_height_m", "must be finite");
  if (!(std::isfinite(standoff_m) && standoff_m > 0)) {
    fail("standoff_m", "must be > 0, got " + std::to_string(standoff_m));
  }
  if (rolls < 1) fail("rolls", "must be >= 1, got " + std::to_string(rolls));
  if (ik_restarts < 0) fail("ik_restarts", "must be >= 0, got " + std::to_string(ik_restarts));
  if (orientations_per_point < 1 || orientations_per_point > 8) {
    fail("orientations_per_point", "must be in 1..8, got " + std::to_string(orientations_per_point));
  }
  if (!(tilt_deg > 0 && tilt_deg < 90)) {
    fail("tilt_deg", "must be in (0, 90), got " + std::to_string(tilt_deg));
  }
}

TaughtPoints TeachPoints(const std::array<KinematicModel, 2>& tip_models,
                         const Transform& X_B1B2_rough, const std::vector<Vector3>& p_B1,
                         const std::array<JointVector, 2>& q_seed, const TeachOptions& options) {
  options.Validate();
  TaughtPoints out;
  for (size_t i = 0; i < p_B1.size(); ++i) {
    // A scenario's points are finite numbers where they are read (bench/io/yaml_util.cc).
    TWIN_REQUIRE(p_B1[i].allFinite(), "p_B1[" + std::to_string(i) + "] must be finite");
    const Teach t = TeachOne(tip_models, X_B1B2_rough, p_B1[i],
                             TipDirection(tip_models, X_B1B2_rough, p_B1[i], 0, options), q_seed,
                             options);
    if (!t.ok) {
      out.rejected.push_back("point " + std::to_string(i) + " " + Mm(p_B1[i]) + ": " + t.reason);
      continue;
    }
    out.p_B1.push_back(p_B1[i]);
    out.q1.push_back(t.q1);
    ++out.points;
    for (int k = 1; k < options.orientations_per_point; ++k) {
      const Teach tk = TeachOne(tip_models, X_B1B2_rough, p_B1[i],
                                TipDirection(tip_models, X_B1B2_rough, p_B1[i], k, options),
                                {t.q1, q_seed[1]}, options);
      if (tk.ok) {
        out.p_B1.push_back(p_B1[i]);
        out.q1.push_back(tk.q1);
      } else {
        out.rejected.push_back("point " + std::to_string(i) + " orientation " +
                               std::to_string(k) + ": " + tk.reason);
      }
    }
  }
  const size_t needed = std::min<size_t>(options.min_points, std::max<size_t>(p_B1.size(), kMinContacts));
  out.ok = static_cast<size_t>(out.points) >= needed;
  if (!out.ok) {
    out.reason = "only " + std::to_string(out.points) + " of " + std::to_string(p_B1.size()) +
                 " handclasp points are reachable by both robots, need " + std::to_string(needed);
  }
  return out;
}

TaughtPoints PlanTaughtPoints(const std::array<KinematicModel, 2>& tip_models,
                              const Transform& X_B1B2_rough,
                              const std::array<JointVector, 2>& q_seed,
                              const TeachOptions& options) {
  options.Validate();
  const Vector3 s1 = Shoulder(tip_models[0]);
  const Vector3 s2 = X_B1B2_rough * Shoulder(tip_models[1]);
  const Vector3 e1 = (s2 - s1).normalized();
  const Vector3 e2 = Perpendicular(e1);
  const Vector3 e3 = e1.cross(e2);
  const Vector3 centre = 0.5 * (s1 + s2);
  TaughtPoints last;
  last.reason = "no cube side tried";
  for (const double side : options.cube_sides_m) {
    std::vector<Vector3> corners;
    for (int c = 0; c < 8; ++c) {
      corners.push_back(centre + 0.5 * side *
                                     ((c & 1 ? 1.0 : -1.0) * e1 + (c & 2 ? 1.0 : -1.0) * e2 +
                                      (c & 4 ? 1.0 : -1.0) * e3));
    }
    // Lift the cube so that its lowest corner keeps min_height_m.
    double lowest = std::numeric_limits<double>::infinity();
    for (const Vector3& p : corners) lowest = std::min(lowest, p.z());
    if (lowest < options.min_height_m) {
      for (Vector3& p : corners) p.z() += options.min_height_m - lowest;
    }
    TaughtPoints t = TeachPoints(tip_models, X_B1B2_rough, corners, q_seed, options);
    t.cube_side_m = side;
    if (t.ok) return t;
    last = t;
  }
  last.ok = false;
  last.reason = "no cube of the sides tried has " + std::to_string(options.min_points) +
                " corners reachable by both robots; smallest: " + last.reason;
  return last;
}

void HandclaspOptions::Validate() const {
  base.Validate();
  ValidateIkOptions(ik);
  // No user sets it: a bad value is our bug.
  TWIN_REQUIRE(std::isfinite(retract_m) && retract_m >= 0,
               "retract_m must be >= 0, got " + std::to_string(retract_m));
}

const char* ToString(HandclaspResult::Status status) {
  using S = HandclaspResult::Status;
  switch (status) {
    case S::kSuccess: return "kSuccess";
    case S::kTooFewContacts: return "kTooFewContacts";
    case S::kCalibrationFailed: return "kCalibrationFailed";
  }
  return "unknown";
}

HandclaspResult RunHandclaspProcedure(Cell& cell,
                                      const std::array<KinematicModel, 2>& pendant_tip_models,
                                      const std::vector<JointVector>& taught_q1,
                                      const HandclaspOptions& options, std::ostream* log) {
  options.Validate();
  RequireFiniteTaughtAngles(taught_q1);
  HandclaspResult result;
  // Robot 2's pose before the first contact: where it returns after each one.
  const ContactSession session{cell, pendant_tip_models, options, log, cell.ReadEncoders(1)};
  // Robot 1 to each taught point, robot 2 jogged onto it; failures are skipped.
  RegisterContacts(session, taught_q1, &result);
  // At least kMinContacts contacts (paper section 2.2).
  if (!HasEnoughContacts(taught_q1.size(), &result)) return result;
  // X_B1B2, general and installation-constrained, from the contact pairs.
  if (!CalibrateFromContacts(options, log, &result)) return result;
  // Optionally X_B1B2 jointly with both tips on their flanges (beyond the paper).
  if (options.identify_tips) IdentifyTips(pendant_tip_models, options.tips, log, &result);
  result.status = HandclaspResult::Status::kSuccess;
  return result;
}

}  // namespace twin
