#include "sim/world/mjcf_writer.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "calib/kinematics/forward_kinematics.h"
#include "calib/common/text_format.h"
#include "sim/world/board_mjcf.h"
#include "sim/render/camera_image.h"

namespace twin {
namespace {

constexpr double kCameraMassKg = 0.3;           // camera body on the active flange
constexpr double kCameraHalf[3] = {0.03, 0.025, 0.02};  // camera housing half sizes [m]
constexpr double kCameraBackoff = 0.005;        // housing front face behind the lens [m]
constexpr double kBaseRadius = 0.09;            // base pedestal [m]
constexpr double kBaseHeight = 0.06;            // [m]
constexpr double kExcludeClearance = 0.01;      // [m], see NecessarilyTouch
constexpr double kTipDensity = 7800.0;          // steel measuring tip [kg/m^3]
constexpr double kMinSegment = 1e-6;            // shorter link segments get no capsule [m]
constexpr double kFlangeThickness = kFlangeThicknessM;  // flange disc at the end of link 6
constexpr int kOverviewWidth = 1600;            // largest overview render [px]
constexpr int kOverviewHeight = 1200;
constexpr double kOverviewFar = 10.0;           // far plane of overview renders [m]

// Capsule radius of link i (0-based joint index) of an n-joint arm [m]: heavier proximal links
// are thicker (a six-axis arm's table; other chains taper linearly over the same range).
double LinkRadius(int joint_index, int n) {
  constexpr double kRadii6[6] = {0.055, 0.05, 0.045, 0.04, 0.04, 0.035};
  const int i = std::clamp(joint_index, 0, n - 1);
  if (n == 6) return kRadii6[i];
  return n == 1 ? kRadii6[0] : kRadii6[0] + (kRadii6[5] - kRadii6[0]) * i / (n - 1);
}

std::string Num(double v) { return ShortestNumber(v); }

std::string Vec(const Vector3& v) { return Num(v.x()) + " " + Num(v.y()) + " " + Num(v.z()); }

Transform RotZ(double angle) {
  return Transform(Eigen::AngleAxisd(angle, Vector3::UnitZ()));
}

Transform RotX(double angle) {
  return Transform(Eigen::AngleAxisd(angle, Vector3::UnitX()));
}

// pos="..." quat="w x y z" of a child frame in its parent.
std::string PoseAttrs(const Transform& X) {
  const Eigen::Quaterniond q(X.linear());
  return "pos=\"" + Vec(X.translation()) + "\" quat=\"" + Num(q.w()) + " " + Num(q.x()) + " " +
         Num(q.y()) + " " + Num(q.z()) + "\"";
}

// M_i of link i: eq. 2 without the joint rotation (theta = 0).
Transform LinkM(const DhParameters& dh) {
  DhParameters no_theta = dh;
  no_theta.theta_offset = 0.0;
  return LinkTransform(no_theta, 0.0);
}

std::string Prefix(int robot) { return "robot" + std::to_string(robot + 1) + "_"; }

// Collision bits: robot k's links and tools are type 1 << k and collide with both robots and
// with the other robot's measuring tip (type 4 << (1 - k)); a tip collides with neither its own
// robot (it sits inside the flange) nor the other tip (handclasp contacts are the point).
std::string RobotContact(int robot) {
  return "contype=\"" + std::to_string(1 << robot) + "\" conaffinity=\"" +
         std::to_string(3 | (4 << (1 - robot))) + "\"";
}
std::string TipContact(int robot) {
  return "contype=\"" + std::to_string(4 << robot) + "\" conaffinity=\"0\"";
}

// Mass properties used for link `link` (0..5) and for the damping estimate.
LinkInertia UsedInertia(const Link& link) {
  if (link.inertia.mass > 0.0) return link.inertia;
  LinkInertia fallback;
  fallback.mass = kFallbackLinkMassKg;
  fallback.I_Com = kFallbackLinkInertiaKgm2 * Matrix3::Identity();
  return fallback;
}

// <inertial> of mass properties given in frame A, written in the body frame U with X_UA.
std::string Inertial(const LinkInertia& in, const Transform& X_UA) {
  const Vector3 com = X_UA * in.p_LiCom;
  const Matrix3 R = X_UA.linear();
  const Matrix3 I = R * in.I_Com * R.transpose();
  return "<inertial pos=\"" + Vec(com) + "\" mass=\"" + Num(in.mass) + "\" fullinertia=\"" +
         Num(I(0, 0)) + " " + Num(I(1, 1)) + " " + Num(I(2, 2)) + " " + Num(I(0, 1)) + " " +
         Num(I(0, 2)) + " " + Num(I(1, 2)) + "\"/>\n";
}

std::string Capsule(const std::string& name, const Vector3& from, const Vector3& to, double r,
                    const std::string& material, const std::string& contact) {
  return "<geom name=\"" + name + "\" type=\"capsule\" fromto=\"" + Vec(from) + " " + Vec(to) +
         "\" size=\"" + Num(r) + "\" material=\"" + material + "\" " + contact + "/>\n";
}

std::string Site(const std::string& name, const Transform& X) {
  // Group 4 is hidden by MuJoCo's default visual options: sites never show in images.
  return "<site name=\"" + name + "\" " + PoseAttrs(X) +
         " size=\"0.005\" group=\"4\" rgba=\"0 0 0 0\"/>\n";
}

// Bodies i and i+2 whose capsules both reach the ends of a short middle link always overlap
// (e.g. links 4 and 6 around a spherical wrist): the distance between the end of body i's
// segment and the start of body i+2's is the length of link i+1, whatever the joint angles.
bool NecessarilyTouch(const KinematicModel& m, int joint_index) {
  const DhParameters& mid = m.links[joint_index + 1].dh;
  const double length = std::hypot(mid.d, mid.a);
  const int n = m.num_joints();
  return length < LinkRadius(joint_index, n) + LinkRadius(joint_index + 2, n) + kExcludeClearance;
}

// A rigid part of the arm for the damping estimate, in the base frame B.
struct Part {
  int link;        // 0..N-1: moves with joints 0..link
  double mass;     // [kg]
  Vector3 com;     // [m] in B
  Matrix3 I;       // about com, axes of B [kg m^2]
};

// The rigid parts of robot `robot` at its initial pose, in its base frame B: links, tool, and
// camera and board as point masses.
std::vector<Part> Parts(const TwinSpec& spec, int robot, const KinematicModel& m) {
  const int n = m.num_joints();
  const FrameSet f = ForwardKinematics(m, spec.robots[robot].q_initial);
  std::vector<Part> parts;
  const auto add = [&](int link, const LinkInertia& in, const Transform& X_BA) {
    parts.push_back({link, in.mass, X_BA * in.p_LiCom,
                     X_BA.linear() * in.I_Com * X_BA.linear().transpose()});
  };
  for (int i = 0; i < n; ++i) add(i, UsedInertia(m.links[i]), f.X_BL[i + 1]);
  add(n - 1, m.tool().inertia, f.tool());
  const Transform& X_BF = f.flange();
  if (spec.HasCameraAndBoard() && spec.camera.robot == robot) {
    parts.push_back({n - 1, kCameraMassKg, X_BF * spec.camera.X_FC.translation(),
                     Matrix3::Zero()});
  }
  if (spec.HasCameraAndBoard() && spec.board.robot == robot) {
    parts.push_back({n - 1, spec.board.mass_kg, X_BF * spec.board.X_FT.translation(),
                     Matrix3::Zero()});
  }
  return parts;
}

// `sum` plus the inertia of the parts on links >= `first_link` about the axis through `o` along
// unit `n` (in B) [kg m^2].
double InertiaAbout(const std::vector<Part>& parts, int first_link, const Vector3& o,
                    const Vector3& n, double sum = 0.0) {
  for (const Part& p : parts) {
    if (p.link < first_link) continue;
    const Vector3 r = p.com - o;
    const Vector3 r_perp = r - r.dot(n) * n;
    sum += n.dot(p.I * n) + p.mass * r_perp.squaredNorm();
  }
  return sum;
}

// Diagonal of the joint-space inertia at the initial pose (the composite inertia outboard of
// each joint about its axis; camera and board as point masses) plus armature [kg m^2].
std::vector<double> EffectiveInertia(const TwinSpec& spec, int robot, const KinematicModel& m) {
  const std::vector<Part> parts = Parts(spec, robot, m);
  const FrameSet f = ForwardKinematics(m, spec.robots[robot].q_initial);
  std::vector<double> inertia(m.num_joints());
  for (int j = 0; j < m.num_joints(); ++j) {
    inertia[j] = InertiaAbout(parts, j, f.X_BL[j].translation(), f.X_BL[j].linear().col(2),
                              spec.physics.armature);
  }
  return inertia;
}

// Two spring hinges "<name>_x", "<name>_y" at the body origin about the body's x and y axes,
// of stiffness k [N m/rad], for a body whose outboard inertia about them is about `inertia`
// [kg m^2] (at the initial pose): armature keeps omega * dt <= kMaxTiltOmegaDt whatever the
// pose (the stiffness is explicit in MuJoCo's Euler step), damping makes them near critical.
std::string TiltHinges(const std::string& name, double k, double inertia, double dt) {
  if (!(k > 0.0)) return "";
  const double armature = k * dt * dt / (kMaxTiltOmegaDt * kMaxTiltOmegaDt);
  const double damping = CriticalDamping(k, inertia + armature);
  std::string x;
  for (const char* axis : {"x", "y"}) {
    x += "<joint name=\"" + name + "_" + axis + "\" type=\"hinge\" pos=\"0 0 0\" axis=\"" +
         (axis[0] == 'x' ? "1 0 0" : "0 1 0") + "\" limited=\"false\" stiffness=\"" + Num(k) +
         "\" springref=\"0\" damping=\"" + Num(damping) + "\" armature=\"" + Num(armature) +
         "\"/>\n";
  }
  return x;
}

// Textures and materials: the cell's, and the orange and grey of each of its `num_robots`.
std::string Assets(int num_robots) {
  static const char* const kOrange[2] = {"0.93 0.42 0.08", "0.96 0.62 0.18"};
  static const char* const kGrey[2] = {"0.45 0.46 0.48", "0.62 0.63 0.66"};
  std::string x =
      "<texture name=\"sky\" type=\"skybox\" builtin=\"gradient\" rgb1=\"0.78 0.82 0.88\""
      " rgb2=\"0.35 0.38 0.44\" width=\"64\" height=\"64\"/>\n"
      "<material name=\"floor\" rgba=\"0.62 0.63 0.65 1\" specular=\"0\" shininess=\"0\"/>\n"
      "<material name=\"base\" rgba=\"0.22 0.23 0.25 1\" specular=\"0.2\"/>\n";
  for (const auto* colours : {&kOrange, &kGrey}) {
    const std::string name = colours == &kOrange ? "orange" : "grey";
    for (int k = 0; k < num_robots; ++k) {
      x += "<material name=\"" + Prefix(k) + name + "\" rgba=\"" + (*colours)[k] +
           " 1\" specular=\"0.3\"/>\n";
    }
  }
  return x + "<material name=\"camera\" rgba=\"0.08 0.08 0.09 1\" specular=\"0.4\"/>\n"
             "<material name=\"tip\" rgba=\"0.8 0.8 0.82 1\" specular=\"0.6\"/>\n";
}

// Geoms of link body i (0-based joint index) in its frame U_i: capsules from the joint axis
// along z by d, then along x by a, ending on the next joint axis.
std::string LinkGeoms(const KinematicModel& m, int robot, int i) {
  const std::string p = Prefix(robot);
  const DhParameters& dh = m.links[i].dh;
  const double r = LinkRadius(i, m.num_joints());
  const std::string material = p + ((i == 0 || i == 1 || i == 3) ? "orange" : "grey");
  const std::string contact = RobotContact(robot);
  const std::string name = p + "link" + std::to_string(i + 1);
  const bool flange = i == m.num_joints() - 1;
  // On the flange link an `a` shorter than the radius (a geometry error, not a real offset) is
  // covered by the flange disc, which sits at the true face; a capsule along it would end in a
  // rounded cap in front of the face.
  const bool has_a = std::abs(dh.a) > (flange ? r : kMinSegment);
  Vector3 p0 = Vector3::Zero(), p1(0, 0, dh.d), p2(dh.a, 0, dh.d);
  // The flange link ends in a flat disc at L6: its capsule stops one radius short of the face
  // so that no rounded cap pokes through a tool mounted on the face.
  if (flange && !has_a) p1.z() -= std::copysign(std::min(r, std::abs(dh.d)), dh.d);
  std::string xml;
  if ((p1 - p0).norm() > kMinSegment) xml += Capsule(name + "_d", p0, p1, r, material, contact);
  if (has_a) xml += Capsule(name + "_a", p1, p2, r, material, contact);
  if (flange) {
    const Vector3 face(dh.a, 0, dh.d);
    const Vector3 back = face - std::copysign(kFlangeThickness, dh.d) * Vector3::UnitZ();
    xml += "<geom name=\"" + name + "_flange\" type=\"cylinder\" fromto=\"" + Vec(back) + " " +
           Vec(face) + "\" size=\"" + Num(r) + "\" material=\"" + p + "grey\" " + contact + "/>\n";
  }
  if (xml.empty()) {  // zero-length link (spherical wrist): a knuckle along the joint axis
    xml = Capsule(name + "_knuckle", Vector3(0, 0, -r), Vector3(0, 0, r), r, material, contact);
  }
  return xml;
}

// Tool, camera, board and tip bodies on the flange (body 6 frame U6; X_U6F = M_6).
// Three spring-loaded slide joints along the flange axes, for a target body of mass `mass` whose
// frame is X_FT in the flange: static deflection `d` (per flange axis) under 1 g.
std::string MountJoints(const std::string& p, const MountCompliance& mount, double mass,
                        const Matrix3& R_FT, double dt) {
  if (!mount.any()) return "";
  std::string x;
  const char* axes[3] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    const double d = mount.deflection_F(i);
    if (!(d > 0.0)) continue;
    const double k = mass * 9.81 / d;  // MJCF gravity is 9.81 m/s^2 (WriteTwinMjcf)
    const double armature =
        std::max(0.0, k * dt * dt / (kMaxMountOmegaDt * kMaxMountOmegaDt) - mass);
    const double damping = 2.0 * std::sqrt(k * (mass + armature));
    const Vector3 axis = R_FT.transpose().col(i);  // flange axis i in the board frame
    x += "<joint name=\"" + p + "mount_" + axes[i] + "\" type=\"slide\" pos=\"0 0 0\" axis=\"" +
         Vec(axis) + "\" limited=\"false\" stiffness=\"" + Num(k) +
         "\" springref=\"0\" damping=\"" + Num(damping) + "\" armature=\"" + Num(armature) +
         "\"/>\n";
  }
  return x;
}

std::string FlangeBodies(const TwinSpec& spec, const Intrinsics& canvas,
                         const KinematicModel& m, int robot, const Transform& X_UF,
                         const MountCompliance& mount) {
  const std::string p = Prefix(robot);
  std::ostringstream x;
  if (m.tool().inertia.mass > 0.0) {
    const Transform X_UL7 = X_UF * LinkTransform(m.tool().dh, 0.0);
    x << "<body name=\"" << p << "tool\" " << PoseAttrs(X_UL7) << ">\n"
      << Inertial(m.tool().inertia, Transform::Identity()) << "</body>\n";
  }
  if (spec.HasCameraAndBoard() && spec.camera.robot == robot) {
    // MJCF cameras look along -z with y up; the OpenCV optical frame is that turned by RotX(pi).
    const Transform X_UC = X_UF * spec.camera.X_FC;
    const double fovy_deg = RadToDeg(2.0 * std::atan(0.5 * canvas.height / canvas.fy));
    x << "<camera name=\"" << kHandCameraName << "\" mode=\"fixed\" " << PoseAttrs(X_UC * RotX(kPi))
      << " fovy=\"" << Num(fovy_deg) << "\"/>\n";
    // Housing behind the lens (optical z < 0): never in view.
    const double hz = kCameraHalf[2];
    const double zc = -kCameraBackoff - hz;
    const double mass = kCameraMassKg;
    const double hx = kCameraHalf[0], hy = kCameraHalf[1];
    x << "<body name=\"" << p << "camera\" " << PoseAttrs(X_UC) << ">\n"
      << "<inertial pos=\"0 0 " << Num(zc) << "\" mass=\"" << Num(mass) << "\" diaginertia=\""
      << Num(mass / 3 * (hy * hy + hz * hz)) << " " << Num(mass / 3 * (hx * hx + hz * hz)) << " "
      << Num(mass / 3 * (hx * hx + hy * hy)) << "\"/>\n"
      << "<geom name=\"" << p << "camera_housing\" type=\"box\" pos=\"0 0 " << Num(zc)
      << "\" size=\"" << Num(hx) << " " << Num(hy) << " " << Num(hz)
      << "\" material=\"camera\" " << RobotContact(robot) << "/>\n</body>\n";
  }
  if (spec.HasCameraAndBoard() && spec.board.robot == robot) {
    // The board's collidable plate takes the robot's collision bits from the child class.
    x << "<body name=\"" << p << "board\" childclass=\"" << p << "contact\" "
      << PoseAttrs(X_UF * spec.board.X_FT) << ">\n"
      << MountJoints(p, mount, spec.board.mass_kg, spec.board.X_FT.linear(),
                     spec.physics.timestep_s)
      << BoardGeomsMjcf(spec.board, p + "board_") << "</body>\n";
  }
  const TipSpec& tip = spec.tips[robot];
  x << "<body name=\"" << p << "tip\" " << PoseAttrs(X_UF * tip.X_FTip) << ">\n"
    << Site(p + "tip", Transform::Identity());
  // Capsule behind the tip point, its rounded end touching the point.
  const double r = tip.radius_m;
  const std::string common = "\" size=\"" + Num(r) + "\" density=\"" + Num(kTipDensity) +
                             "\" material=\"tip\" " + TipContact(robot) + "/>\n";
  if (tip.length_m > 2.0 * r) {
    x << "<geom name=\"" << p << "tip\" type=\"capsule\" fromto=\"0 0 " << Num(-tip.length_m)
      << " 0 0 " << Num(-r) << common;
  } else {
    x << "<geom name=\"" << p << "tip\" type=\"sphere\" pos=\"0 0 " << Num(-r) << common;
  }
  x << "</body>\n";
  return x.str();
}

// Outboard inertia about the x and y axes of frame X_BA through its origin, averaged (the
// damping estimate of a pair of tilt hinges) [kg m^2].
double TiltInertia(const std::vector<Part>& parts, int first_link, const Transform& X_BA) {
  return 0.5 * (InertiaAbout(parts, first_link, X_BA.translation(), X_BA.linear().col(0)) +
                InertiaAbout(parts, first_link, X_BA.translation(), X_BA.linear().col(1)));
}

std::string Robot(const TwinSpec& spec, const Intrinsics& canvas, const KinematicModel& m,
                  const std::vector<JointDrive>& drives, const MountCompliance& mount,
                  const StructureCompliance& structure, int robot) {
  const std::string p = Prefix(robot);
  const PhysicsSpec& phys = spec.physics;
  const std::vector<double> inertia = EffectiveInertia(spec, robot, m);
  const std::vector<Part> parts = Parts(spec, robot, m);
  const FrameSet f0 = ForwardKinematics(m, spec.robots[robot].q_initial);
  const int n = m.num_joints();
  const auto tilt_stiffness = [&](int i) {
    const std::vector<double>& k = structure.joint_tilt_stiffness;
    return i < static_cast<int>(k.size()) ? k[i] : 0.0;
  };
  std::ostringstream x;
  x << "<body name=\"" << p << "base\" " << PoseAttrs(spec.robots[robot].X_WB) << ">\n"
    << TiltHinges(p + "base_tilt", structure.base_tilt_stiffness,
                  TiltInertia(parts, 0, Transform::Identity()), phys.timestep_s)
    << "<geom name=\"" << p << "base\" type=\"cylinder\" pos=\"0 0 " << Num(kBaseHeight / 2)
    << "\" size=\"" << Num(kBaseRadius) << " " << Num(kBaseHeight / 2) << "\" material=\"base\" "
    << RobotContact(robot) << "/>\n"
    << Site(p + "L0", m.X_BL0);
  Transform X_parent_child = m.X_BL0 * RotZ(m.links[0].dh.theta_offset);
  for (int i = 0; i < n; ++i) {
    const Link& link = m.links[i];
    const Transform M = LinkM(link.dh);
    x << "<body name=\"" << p << "link" << i + 1 << "\" " << PoseAttrs(X_parent_child) << ">\n"
      << TiltHinges(p + "j" + std::to_string(i + 1) + "_tilt", tilt_stiffness(i),
                    TiltInertia(parts, i, f0.X_BL[i] * RotZ(link.dh.theta_offset)),
                    phys.timestep_s)
      << "<joint name=\"" << p << "j" << i + 1 << "\" type=\"hinge\" pos=\"0 0 0\" axis=\"0 0 1\""
      << " limited=\"true\" range=\"" << Num(link.limits.lower) << " " << Num(link.limits.upper)
      << "\" armature=\"" << Num(phys.armature) << "\" damping=\""
      << Num(CriticalDamping(drives[i].stiffness, inertia[i])) << "\"/>\n"
      << Inertial(UsedInertia(link), M) << LinkGeoms(m, robot, i)
      << Site(p + "L" + std::to_string(i + 1), M);
    if (i + 1 < n) {
      X_parent_child = M * RotZ(m.links[i + 1].dh.theta_offset);
    } else {
      x << Site(p + "L" + std::to_string(n + 1), M * LinkTransform(m.tool().dh, 0.0))
        << FlangeBodies(spec, canvas, m, robot, M, mount);
    }
  }
  for (int i = 0; i < n; ++i) x << "</body>\n";
  x << "</body>\n";
  return x.str();
}

}  // namespace

double FlangeRadius(int num_joints) { return LinkRadius(num_joints - 1, num_joints); }

double CriticalDamping(double kp, double inertia) { return 2.0 * std::sqrt(kp * inertia); }

std::string WriteTwinMjcf(const TwinSpec& spec, const std::array<KinematicModel, 2>& true_models,
                          const std::array<std::vector<JointDrive>, 2>& drives,
                          const std::array<MountCompliance, 2>& mounts,
                          const std::array<StructureCompliance, 2>& structures) {
  const bool camera = spec.HasCameraAndBoard();
  // Without a hand camera the off-screen buffer, samples and clipping serve overviews only:
  // CameraSpec's defaults.
  const CameraSpec view = camera ? spec.camera : CameraSpec{};
  const Intrinsics canvas =
      camera ? DistortionMapper(spec.camera.intrinsics, spec.camera.distortion).canvas()
             : Intrinsics{kOverviewWidth, kOverviewHeight};
  Vector3 mid = Vector3::Zero();  // the centre of the bases
  for (int k = 0; k < spec.num_robots; ++k) mid += spec.robots[k].X_WB.translation();
  mid /= spec.num_robots;
  std::ostringstream x;
  x << "<mujoco model=\"twin_cell\">\n"
    << "<compiler angle=\"radian\" balanceinertia=\"true\" inertiafromgeom=\"auto\"/>\n"
    << "<option timestep=\"" << Num(spec.physics.timestep_s) << "\" gravity=\"0 0 "
    << (spec.physics.gravity ? "-9.81" : "0") << "\" integrator=\"Euler\"/>\n"
    << "<size njmax=\"2000\" nconmax=\"500\"/>\n"
    // extent 1 makes <map znear/zfar> clipping distances in metres: the hand camera's near
    // plane, and a far plane that also covers overview renders.
    << "<statistic extent=\"1\" center=\"" << Vec(mid) << "\"/>\n"
    << "<visual>\n"
    << "<global offwidth=\"" << std::max(canvas.width, kOverviewWidth) << "\" offheight=\""
    << std::max(canvas.height, kOverviewHeight) << "\"/>\n"
    << "<quality offsamples=\"" << view.msaa_samples << "\"/>\n"
    << "<map znear=\"" << Num(view.near_m) << "\" zfar=\""
    << Num(std::max(view.far_m, kOverviewFar)) << "\"/>\n"
    << "<headlight ambient=\"0.3 0.3 0.3\" diffuse=\"0.45 0.45 0.45\""
    << " specular=\"0.05 0.05 0.05\"/>\n"
    << "</visual>\n";
  x << "<default>\n";
  for (int k = 0; k < spec.num_robots; ++k) {
    x << "<default class=\"" << Prefix(k) << "contact\"><geom " << RobotContact(k)
      << "/></default>\n";
  }
  x << "</default>\n";
  x << "<asset>\n" << Assets(spec.num_robots) << (camera ? BoardAssetsMjcf(spec.board) : "")
    << "</asset>\n";
  x << "<worldbody>\n"
    << "<geom name=\"floor\" type=\"plane\" pos=\"" << Num(mid.x()) << " " << Num(mid.y())
    << " 0\" size=\"4 4 0.05\" material=\"floor\" contype=\"0\" conaffinity=\"0\"/>\n"
    << "<light name=\"key\" directional=\"true\" castshadow=\"false\" pos=\"" << Num(mid.x())
    << " " << Num(mid.y()) << " 4\" dir=\"0.3 0.2 -1\" diffuse=\"0.5 0.5 0.5\""
    << " specular=\"0.2 0.2 0.2\"/>\n"
    << "<light name=\"fill\" directional=\"true\" castshadow=\"false\" pos=\"" << Num(mid.x())
    << " " << Num(mid.y()) << " 4\" dir=\"-0.4 -0.5 -0.6\" diffuse=\"0.25 0.25 0.25\""
    << " specular=\"0 0 0\"/>\n";
  for (int k = 0; k < spec.num_robots; ++k) {
    x << Robot(spec, canvas, true_models[k], drives[k], mounts[k], structures[k], k);
  }
  x << "</worldbody>\n<contact>\n";
  for (int k = 0; k < spec.num_robots; ++k) {
    // MuJoCo's parent filter skips pairs with a static body: the base needs an explicit one.
    x << "<exclude body1=\"" << Prefix(k) << "base\" body2=\"" << Prefix(k) << "link1\"/>\n";
    for (int i = 0; i + 2 < true_models[k].num_joints(); ++i) {
      if (!NecessarilyTouch(true_models[k], i)) continue;
      x << "<exclude body1=\"" << Prefix(k) << "link" << i + 1 << "\" body2=\"" << Prefix(k)
        << "link" << i + 3 << "\"/>\n";
    }
  }
  x << "</contact>\n<actuator>\n";
  for (int k = 0; k < spec.num_robots; ++k) {
    for (int i = 0; i < true_models[k].num_joints(); ++i) {
      x << "<position name=\"" << Prefix(k) << "a" << i + 1 << "\" joint=\"" << Prefix(k) << "j"
        << i + 1 << "\" kp=\"" << Num(drives[k][i].stiffness) << "\" ctrllimited=\"false\"/>\n";
    }
  }
  x << "</actuator>\n</mujoco>\n";
  return x.str();
}

}  // namespace twin
