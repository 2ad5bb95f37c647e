#include "calib/kinematics/spherical_wrist_ik.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "calib/kinematics/forward_kinematics.h"

namespace twin {
namespace {

// Subproblems' degenerate cases: a vector shorter than this [m or unit length] has no direction.
constexpr double kTiny = 1e-12;
// A square root or arccosine whose argument is this close to zero is taken as zero: at a
// singular target (joint 5 straight, the elbow stretched) the argument is rounding noise of
// ~1e-16, whose square root (~1e-8) would tilt both answers off the target by more than the
// check below and lose them; a target this close to a singularity gives one answer there.
constexpr double kSingular = 1e-7;
// A solution is kept when forward kinematics reproduces the target to within this [m, rad].
constexpr double kCheckTolerance = 1e-9;

// Rotation about the unit axis w by angle q.
Matrix3 Rot(const Vector3& w, double q) { return Eigen::AngleAxisd(q, w).toRotationMatrix(); }

// Angle in (-pi, pi].
double Wrap(double q) {
  q = std::remainder(q, 2.0 * kPi);
  return q <= -kPi ? q + 2.0 * kPi : q;
}

// Subproblem 1: the angle that turns u onto v about the unit axis w (both taken across w).
double TurnOnto(const Vector3& w, const Vector3& u, const Vector3& v) {
  const Vector3 up = u - w * w.dot(u);
  const Vector3 vp = v - w * w.dot(v);
  return std::atan2(w.dot(up.cross(vp)), up.dot(vp));
}

// Distance from point p to the line through r along unit w.
double LineDistance(const Vector3& p, const Vector3& r, const Vector3& w) {
  return (p - r - w * w.dot(p - r)).norm();
}

// The angles q with a cos q + b sin q = c: none, one (tangent) or two.
std::vector<double> CosSinRoots(double a, double b, double c) {
  const double rho = std::hypot(a, b);
  if (rho < kTiny) return {};
  const double x = c / rho;
  if (std::abs(x) > 1.0 + 1e-12) return {};
  const double phi = std::atan2(b, a);
  const double d = std::acos(std::clamp(x, -1.0, 1.0));
  if (d < kSingular) return {phi};
  return {phi + d, phi - d};
}

// Subproblem 3: the angles q that bring e^(w q) (p about the axis through r) to distance delta
// from the point s, written as the cos/sin equation of the point's circle.
std::vector<double> AtDistance(const Vector3& w, const Vector3& r, const Vector3& p,
                               const Vector3& s, double delta) {
  const Vector3 u = p - r;
  const Vector3 v = s - r;
  const Vector3 up = u - w * w.dot(u);
  const Vector3 vp = v - w * w.dot(v);
  // |e^(wq) p - s|^2 = |up|^2 + |vp|^2 - 2 vp . (R up) + (w.(u - v))^2, with
  // vp . (R up) = cos q (up . vp) + sin q (w x up) . vp.
  const double along = w.dot(u - v);
  const double c = (up.squaredNorm() + vp.squaredNorm() + along * along - delta * delta) / 2.0;
  return CosSinRoots(up.dot(vp), w.cross(up).dot(vp), c);
}

// Subproblem 2 for directions: the angle pairs (q1, q2) with R(w1, q1) R(w2, q2) p = q for unit
// vectors p, q and non-parallel unit axes w1, w2 (through one point).
std::vector<std::pair<double, double>> TurnTwice(const Vector3& w1, const Vector3& w2,
                                                 const Vector3& p, const Vector3& q) {
  const double c12 = w1.dot(w2);
  const double den = c12 * c12 - 1.0;
  const double alpha = (c12 * w2.dot(p) - w1.dot(q)) / den;
  const double beta = (c12 * w1.dot(q) - w2.dot(p)) / den;
  const Vector3 n = w1.cross(w2);
  const double g2 =
      (p.squaredNorm() - alpha * alpha - beta * beta - 2.0 * alpha * beta * c12) / n.squaredNorm();
  if (g2 < -1e-12) return {};
  std::vector<std::pair<double, double>> out;
  const double g = std::sqrt(std::max(g2, 0.0));
  for (double sign : g > kSingular ? std::vector<double>{1.0, -1.0} : std::vector<double>{0.0}) {
    // z: the intermediate direction, R(w2, q2) p = z = R(w1, -q1) q.
    const Vector3 z = alpha * w1 + beta * w2 + sign * g * n;
    out.push_back({TurnOnto(w1, z, q), TurnOnto(w2, p, z)});
  }
  return out;
}

double AxisAngle(const Vector3& a, const Vector3& b) { return a.cross(b).norm(); }

// Each joint of q turned by whole turns to the angle inside its limits nearest the seed's
// (limits may be wider than a turn, or lopsided: KUKA's A2 is -190..45 deg, where a solution
// at 175 deg is the joint at -185 deg); false when some joint has no such angle.
bool TurnsInsideLimits(const KinematicModel& model, const JointVector& seed, JointVector* q) {
  for (int i = 0; i < q->size(); ++i) {
    const JointLimits& l = model.links[i].limits;
    const double turn = 2.0 * kPi;
    // The turns k with lower <= q + k turn <= upper, and of those the nearest to the seed.
    const double k_low = std::ceil((l.lower - (*q)(i)) / turn - 1e-12);
    const double k_high = std::floor((l.upper - (*q)(i)) / turn + 1e-12);
    if (k_low > k_high) return false;
    const double k_seed = std::round((seed(i) - (*q)(i)) / turn);
    (*q)(i) += std::clamp(k_seed, k_low, k_high) * turn;
    (*q)(i) = std::clamp((*q)(i), l.lower, l.upper);  // the 1e-12 slack above
  }
  return true;
}

}  // namespace

std::optional<SphericalWristIk> SphericalWristIk::For(const KinematicModel& model,
                                                      std::string* why, double tolerance) {
  const auto fail = [&](const std::string& reason) {
    if (why) *why = model.name + ": no closed-form IK: " + reason;
    return std::nullopt;
  };
  if (model.num_joints() != 6) {
    return fail(std::to_string(model.num_joints()) + " joints, the closed form takes 6");
  }
  SphericalWristIk ik(model);
  const FrameSet f = ForwardKinematics(model, ZeroJoints(model));
  for (int i = 0; i < 6; ++i) {
    // Joint i + 1 turns about z of frame L_i (eq. 2: RotZ(theta_offset + q) comes first).
    ik.w_[i] = f.X_BL[i].linear().col(2);
    ik.r_[i] = f.X_BL[i].translation();
  }
  ik.X_BE0_ = f.X_BE;
  std::ostringstream os;
  if (AxisAngle(ik.w_[1], ik.w_[2]) > tolerance) {
    os << "joints 2 and 3 are not parallel (" << std::asin(std::min(1.0, AxisAngle(ik.w_[1], ik.w_[2])))
       << " rad apart)";
    return fail(os.str());
  }
  if (AxisAngle(ik.w_[0], ik.w_[1]) < 1e-6) return fail("joints 1 and 2 are parallel");
  if (AxisAngle(ik.w_[3], ik.w_[4]) < 1e-6 || AxisAngle(ik.w_[4], ik.w_[5]) < 1e-6) {
    return fail("two neighbouring wrist axes (4, 5, 6) are parallel");
  }
  // Where axes 4 and 5 come closest (the midpoint of their common perpendicular).
  const Vector3 d = ik.r_[4] - ik.r_[3];
  const Vector3 n = ik.w_[3].cross(ik.w_[4]);
  const double t4 = d.cross(ik.w_[4]).dot(n) / n.squaredNorm();
  const double t5 = d.cross(ik.w_[3]).dot(n) / n.squaredNorm();
  const Vector3 p4 = ik.r_[3] + t4 * ik.w_[3];
  const Vector3 p5 = ik.r_[4] + t5 * ik.w_[4];
  ik.wrist_centre_ = 0.5 * (p4 + p5);
  const double miss45 = (p4 - p5).norm();
  const double miss6 = LineDistance(ik.wrist_centre_, ik.r_[5], ik.w_[5]);
  if (miss45 > tolerance || miss6 > tolerance) {
    os << "the wrist axes do not meet in a point (axes 4 and 5 miss each other by " << miss45
       << " m, axis 6 misses their crossing by " << miss6 << " m)";
    return fail(os.str());
  }
  return ik;
}

std::vector<JointVector> SphericalWristIk::Solve(const Transform& X_BE_target) const {
  std::vector<JointVector> out;
  if (!X_BE_target.matrix().allFinite()) return out;
  // The motion of the chain, g = X_target X_BE(0)^-1 = e^(xi_1 q_1) ... e^(xi_6 q_6).
  const Transform g = X_BE_target * X_BE0_.inverse();
  const Vector3 wc = g * wrist_centre_;  // joints 4-6 leave the wrist centre where it is
  // 1. Joint 1: joints 2 and 3 turn about parallel axes, so the offset of the wrist centre
  // along their direction, from axis 2, is what it is at q = 0 (k); after joint 1 turns by q1,
  // axis 2 is (R1 w2, r1 + R1 (r2 - r1)), so (R1 w2) . (wc - r1) = k + w2 . (r2 - r1).
  const Vector3& w1 = w_[0];
  const Vector3& w2 = w_[1];
  const double k = w2.dot(wrist_centre_ - r_[1]) + w2.dot(r_[1] - r_[0]);
  const Vector3 u = wc - r_[0];
  const Vector3 w2p = w2 - w1 * w1.dot(w2);  // R1 w2 = R1 w2p + w1 (w1.w2)
  const double a = w2p.dot(u), b = w1.cross(w2p).dot(u);
  const double c = k - w1.dot(w2) * w1.dot(u);
  for (double q1 : CosSinRoots(a, b, c)) {
    const Matrix3 R1 = Rot(w1, q1);
    // The wrist centre in the frame of q = 0 as joints 2 and 3 must place it.
    const Vector3 wc1 = r_[0] + R1.transpose() * (wc - r_[0]);
    // 2. Joint 3 from the distance to a point of axis 2, then joint 2.
    const double delta = (wc1 - r_[1]).norm();
    for (double q3 : AtDistance(w_[2], r_[2], wrist_centre_, r_[1], delta)) {
      const Vector3 p3 = r_[2] + Rot(w_[2], q3) * (wrist_centre_ - r_[2]);
      const double q2 = TurnOnto(w2, p3 - r_[1], wc1 - r_[1]);
      // 3. The wrist: R(w4,q4) R(w5,q5) R(w6,q6) = M.
      const Matrix3 M = (R1 * Rot(w2, q2) * Rot(w_[2], q3)).transpose() * g.linear();
      for (const auto& [q4, q5] : TurnTwice(w_[3], w_[4], w_[5], M * w_[5])) {
        // A direction across axis 6, turned by joint 6 alone.
        Vector3 x = w_[5].cross(Vector3::UnitX());
        if (x.norm() < 0.1) x = w_[5].cross(Vector3::UnitY());
        const Matrix3 R45 = Rot(w_[3], q4) * Rot(w_[4], q5);
        const double q6 = TurnOnto(w_[5], x, R45.transpose() * M * x);
        JointVector q(6);
        q << Wrap(q1), Wrap(q2), Wrap(q3), Wrap(q4), Wrap(q5), Wrap(q6);
        const Transform X = EndPose(model_, q);
        const double dp = (X.translation() - X_BE_target.translation()).norm();
        const double dr =
            Eigen::AngleAxisd(X.linear() * X_BE_target.linear().transpose()).angle();
        if (dp <= kCheckTolerance && dr <= kCheckTolerance) out.push_back(q);
      }
    }
  }
  return out;
}

bool SphericalWristIk::Serves(const JointVector& q_seed, const IkOptions& options) const {
  // The closed form answers to 1e-9 m and rad (Solve's check); a caller asking for less gets
  // the iterative solver.
  return !options.position_only && options.position_tolerance >= 1e-9 &&
         options.orientation_tolerance >= 1e-9 && q_seed.size() == model_.num_joints() &&
         q_seed.allFinite() && WithinLimits(model_, q_seed);
}

std::vector<JointVector> SphericalWristIk::InsideLimits(const Transform& X_BE_target,
                                                       const JointVector& q_seed) const {
  std::vector<std::pair<double, JointVector>> inside;
  for (JointVector& q : Solve(X_BE_target)) {
    if (TurnsInsideLimits(model_, q_seed, &q)) inside.emplace_back((q - q_seed).norm(), q);
  }
  std::stable_sort(inside.begin(), inside.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<JointVector> out;
  for (auto& [distance, q] : inside) out.push_back(std::move(q));
  return out;
}

IkResult SphericalWristIk::Nearest(const Transform& X_BE_target, const JointVector& q_seed,
                                   const IkOptions& options) const {
  ValidateIkOptions(options);
  if (!Serves(q_seed, options)) return SolveIk(model_, X_BE_target, q_seed, options);
  const std::vector<JointVector> inside = InsideLimits(X_BE_target, q_seed);
  if (inside.empty()) return SolveIk(model_, X_BE_target, q_seed, options);
  IkResult r;
  r.status = IkStatus::kSuccess;
  r.q = inside.front();
  const Transform X = EndPose(model_, r.q);
  r.position_error = (X.translation() - X_BE_target.translation()).norm();
  r.orientation_error = Eigen::AngleAxisd(X.linear() * X_BE_target.linear().transpose()).angle();
  r.iterations = 0;
  r.starts = 1;
  return r;
}

IkResult SolveIkSphericalWrist(const KinematicModel& model, const Transform& X_BE_target,
                               const JointVector& q_seed, const IkOptions& options) {
  ValidateIkOptions(options);
  std::string why;
  const std::optional<SphericalWristIk> ik = SphericalWristIk::For(model, &why);
  if (!ik) return SolveIk(model, X_BE_target, q_seed, options);
  return ik->Nearest(X_BE_target, q_seed, options);
}

}  // namespace twin
