#include "sim/cell/twin_cell.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <utility>

#include <mujoco/mujoco.h>

#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "calib/kinematics/inverse_kinematics.h"
#include "sim/render/camera_image.h"
#include "sim/world/mjcf_writer.h"
#include "sim/world/mujoco_handles.h"
#include "sim/render/renderer.h"

namespace twin {
namespace {

constexpr int kMaxOverviewWidth = 1600;   // the MJCF's offscreen buffer is sized for these [px]
constexpr int kMaxOverviewHeight = 1200;
// A move that starts in contact (after a collision stop) may back out: contacts present at its
// start are tolerated while they get no deeper than this [m] (the stop halts the robot, so
// only the other robot's servo settling can deepen them, by far less).
constexpr double kBackOutSlack = 1e-4;
// A joint standing off its servo's command by more than this at rest, in a contact, is pressed
// by it [rad]: 0.1 mm at 1 m; ten times the light touch of a board on a link, a fifth of a
// halted arm pressed against its base (TwinCellImpl::Run).
constexpr double kPressedOffRad = 1e-4;

// The Euler step with implicit damping of a critically damped servo is stable while
// omega dt < 2 + 2 sqrt(2) ~ 4.83 (omega = sqrt(kp / M_ii)); measured: armature 0.1 kg m^2 at
// dt = 2 ms holds kp = 5.5e5 (4.69) and diverges at 6e5 (4.90). The margin covers the inertia
// changing with the pose.
constexpr double kMaxOmegaDt = 4.5;

// The simulated operator's handclasp: stand-off in front of the other tip [m], straight
// approach waypoints from there, corrective jogs before giving up, tip-axis rolls tried.
constexpr double kHandclaspStandoff = 0.05;
constexpr int kApproachWaypoints = 5;
constexpr int kMaxCorrectiveJogs = 8;
constexpr int kHandclaspRolls = 8;

// An independent random stream per purpose, so that grabbing images does not change encoder
// noise and vice versa.
std::mt19937_64 Stream(std::uint64_t seed, std::uint32_t stream) {
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    stream};
  return std::mt19937_64(seq);
}

std::string Deg(double rad) {
  std::ostringstream os;
  os.precision(6);
  os << RadToDeg(rad);
  return os.str();
}

Transform FromMj(const mjtNum* pos, const mjtNum* mat) {
  Transform X = Transform::Identity();
  X.translation() = Vector3(pos[0], pos[1], pos[2]);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) X.linear()(r, c) = mat[3 * r + c];
  }
  return X;
}

std::string Prefix(int robot) { return "robot" + std::to_string(robot + 1) + "_"; }

// The simulated operator's own geometry (written here, independently of the estimator's
// handclasp procedure): the true arm whose end frame is the measuring tip on the flange.
KinematicModel TrueTipModel(const KinematicModel& true_model, const Transform& X_FTip) {
  KinematicModel m = true_model;
  m.tool().dh = DhParameters{};  // the tool link frame is the flange
  m.X_LtE = X_FTip;
  return m;
}

// Orientation for the jogged tip facing the other tip (z axes opposed), rolled about its own z.
Matrix3 FacingRotation(const Matrix3& R_W_other_tip, double roll) {
  const Matrix3 flip = Eigen::AngleAxisd(kPi, Vector3::UnitX()).toRotationMatrix();
  return R_W_other_tip * flip * Eigen::AngleAxisd(roll, Vector3::UnitZ()).toRotationMatrix();
}

}  // namespace

struct TwinCell::Impl {
  TwinSpec spec;
  std::string where;
  std::vector<std::unique_ptr<Effect>> effects;
  std::array<KinematicModel, kMaxRobots> models;
  std::array<std::vector<JointDrive>, kMaxRobots> drives;
  std::array<MountCompliance, kMaxRobots> mounts;  // target brackets (mount deflection)
  std::array<StructureCompliance, kMaxRobots> structures;  // bearings and bases on springs
  std::vector<int> passive_dofs;   // dof addresses of the mounts' and supports' spring joints
  // Axis wobble: per robot, whether an effect tilts its axes, and each link body's id and its
  // orientation in the parent as compiled (the twin turns it by the tilt as the joint moves).
  std::array<bool, kMaxRobots> tilts_axes{false, false};
  std::array<std::vector<int>, kMaxRobots> link_body;
  std::array<std::vector<Eigen::Quaterniond>, kMaxRobots> link_quat0;
  std::string mjcf;
  MjModelPtr m;
  MjDataPtr d;
  std::mt19937_64 encoder_rng, image_rng, operator_rng, tracker_rng, temperature_rng;
  double operator_sigma = 0.0;   // operator alignment error per axis [m]
  double last_gap = 0.0;         // jogged tip to aim point after the last contact [m]
  std::array<JointVector, kMaxRobots> motor;      // commanded motor angles [rad]
  std::array<JointVector, kMaxRobots> direction;  // sign of each joint's last motion
  std::array<std::vector<int>, kMaxRobots> qadr, dadr, act;
  std::array<std::vector<int>, kMaxRobots> site_L;
  std::array<int, kMaxRobots> site_tip;
  int camera = -1, board_body = -1;
  BracketTarget mounted = BracketTarget::kFeatureBoard;  // what spec.board is now
  std::optional<DistortionMapper> distortion;     // only when the lens distorts
  Intrinsics canvas;
  std::unique_ptr<OffscreenRenderer> hand_renderer, overview_renderer;
  int last_steps = 0;
  std::atomic<bool> stop_requested{false};  // RequestStop(): the move in progress ends
  bool realtime = false;                    // SetRealtime(): steps paced to wall time
  // Drifting link lengths (thermal drift): the model entries that move with a robot's length
  // scale, each with its value at scale 1 and its slope per unit of scale.
  struct DriftEntry {
    mjtNum* value;
    mjtNum base, slope;
    int robot;
  };
  std::vector<DriftEntry> drift;

  int Joints(int robot) const { return models[robot].num_joints(); }
  int Robots() const { return spec.num_robots; }

  // Throws InputError for `what` (a method that needs the hand camera) on a cell without one.
  void RequireCamera(const std::string& what) const {
    if (spec.HasCameraAndBoard()) return;
    throw InputError(where, what + ": this cell has no hand camera (a one-robot cell has "
                                   "neither camera nor board; it needs two robots)");
  }

  // "robot index 2 is not a robot of this cell (0..1)", or "" for a valid index.
  std::string BadRobot(int robot) const {
    if (robot >= 0 && robot < Robots()) return "";
    return "robot index " + std::to_string(robot) + " is not a robot of this cell (0.." +
           std::to_string(Robots() - 1) + ")";
  }

  // Product of the drifting effects' length scales of robot k at the twin's time t.
  double LengthScale(int k, double t) const {
    double scale = 1.0;
    for (const auto& e : effects) {
      if (e->DriftsLengths(k)) scale *= e->LengthScaleAt(k, t);
    }
    return scale;
  }

  // Finds the drift entries: for each drifting robot, a second world built with its d and a
  // scaled by 1 + kProbe; every position and size that differs between the two is linear in
  // the scale (translations along the links: d z + a x), so the world at any scale is
  // base + slope (scale - 1), exactly. Frames must not turn with the scale (they do not: a
  // uniform growth keeps every direction); a structural difference is our bug.
  void SetUpDrift() {
    drift.clear();
    constexpr double kProbe = 1e-3;
    for (int k = 0; k < Robots(); ++k) {
      bool drifts = false;
      for (const auto& e : effects) drifts = drifts || e->DriftsLengths(k);
      if (!drifts) continue;
      std::array<KinematicModel, kMaxRobots> probe_models = models;
      for (Link& link : probe_models[k].links) {
        link.dh.d *= 1.0 + kProbe;
        link.dh.a *= 1.0 + kProbe;
      }
      const MjModelPtr p =
          LoadMjcfFromString(WriteTwinMjcf(spec, probe_models, drives, mounts, structures));
      if (p->nbody != m->nbody || p->ngeom != m->ngeom || p->nsite != m->nsite ||
          p->ncam != m->ncam || p->njnt != m->njnt) {
        throw std::logic_error("thermal drift: the probe world differs in structure");
      }
      const auto linear = [&](mjtNum* a, const mjtNum* b, int count) {
        for (int i = 0; i < count; ++i) {
          if (b[i] != a[i]) drift.push_back({a + i, a[i], (b[i] - a[i]) / kProbe, k});
        }
      };
      linear(m->body_pos, p->body_pos, 3 * m->nbody);
      linear(m->body_ipos, p->body_ipos, 3 * m->nbody);
      linear(m->jnt_pos, p->jnt_pos, 3 * m->njnt);
      linear(m->geom_pos, p->geom_pos, 3 * m->ngeom);
      linear(m->geom_size, p->geom_size, 3 * m->ngeom);
      linear(m->geom_rbound, p->geom_rbound, m->ngeom);
      linear(m->site_pos, p->site_pos, 3 * m->nsite);
      linear(m->cam_pos, p->cam_pos, 3 * m->ncam);
      const auto same = [&](const mjtNum* a, const mjtNum* b, int count, const char* what) {
        for (int i = 0; i < count; ++i) {
          if (std::abs(a[i] - b[i]) > 1e-12) {
            throw std::logic_error(std::string("thermal drift turns ") + what);
          }
        }
      };
      same(m->body_quat, p->body_quat, 4 * m->nbody, "a body");
      same(m->geom_quat, p->geom_quat, 4 * m->ngeom, "a geom");
      same(m->site_quat, p->site_quat, 4 * m->nsite, "a site");
      same(m->cam_quat, p->cam_quat, 4 * m->ncam, "the camera");
    }
  }

  // Moves the drifting robots' bodies to their lengths at the twin's time (call before
  // stepping or mj_forward).
  void ApplyDrift() {
    if (drift.empty()) return;
    std::array<double, kMaxRobots> scale;
    for (int k = 0; k < Robots(); ++k) scale[k] = LengthScale(k, d->time);
    for (const DriftEntry& e : drift) *e.value = e.base + e.slope * (scale[e.robot] - 1.0);
  }

  // Turns the link bodies of robots whose axes wobble by their tilts at the current link-side
  // angles (Effect::AddAxisTilt): the rotation vector (tx, ty, 0) in the parent's DH frame
  // L(i-1) = U_i RotZ(-theta_offset_i), written into body i's orientation in its parent.
  void ApplyWobble() {
    for (int k = 0; k < Robots(); ++k) {
      if (!tilts_axes[k]) continue;
      std::vector<Eigen::Vector2d> tilt(Joints(k), Eigen::Vector2d::Zero());
      const JointVector q = LinkAngles(k);
      for (const auto& e : effects) e->AddAxisTilt(k, q, &tilt);
      for (int i = 0; i < Joints(k); ++i) {
        const Vector3 v_L(tilt[i].x(), tilt[i].y(), 0.0);
        const Vector3 v_U =
            Eigen::AngleAxisd(-models[k].links[i].dh.theta_offset, Vector3::UnitZ()) * v_L;
        const double angle = v_U.norm();
        const Eigen::Quaterniond turn =
            angle > 0.0 ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, v_U / angle))
                        : Eigen::Quaterniond::Identity();
        const Eigen::Quaterniond q_new = link_quat0[k][i] * turn;
        mjtNum* quat = m->body_quat + 4 * link_body[k][i];
        quat[0] = q_new.w();
        quat[1] = q_new.x();
        quat[2] = q_new.y();
        quat[3] = q_new.z();
      }
    }
  }

  // The model changes that follow the twin's clock and pose (drift, wobble): call before
  // stepping or mj_forward, after setting qpos.
  void ApplyModelMotion() {
    ApplyDrift();
    ApplyWobble();
  }

  // Link-side joint angles of robot k now (MuJoCo's qpos).
  JointVector LinkAngles(int k) const {
    JointVector q(Joints(k));
    for (int i = 0; i < Joints(k); ++i) q(i) = d->qpos[qadr[k][i]];
    return q;
  }

  int Id(mjtObj type, const std::string& name) const {
    const int id = mj_name2id(m.get(), type, name.c_str());
    if (id < 0) throw std::logic_error("twin MJCF lacks " + name);  // our bug
    return id;
  }

  std::string BodyName(int geom) const {
    const char* name = mj_id2name(m.get(), mjOBJ_BODY, m->geom_bodyid[geom]);
    return name ? name : "body " + std::to_string(m->geom_bodyid[geom]);
  }

  std::string GeomName(int geom) const {
    const char* name = mj_id2name(m.get(), mjOBJ_GEOM, geom);
    return name ? name : "geom " + std::to_string(geom);
  }

  std::string ContactText(const mjContact& c) const {
    return BodyName(c.geom1) + " touches " + BodyName(c.geom2) + " (geoms " + GeomName(c.geom1) +
           ", " + GeomName(c.geom2) + ")";
  }

  // Contacts between geoms of different bodies (MuJoCo already dropped excluded, parent and
  // contype-filtered pairs). Returns the first one not tolerated by `allowed` (pair -> depth).
  const mjContact* Collision(const std::map<std::pair<int, int>, double>& allowed) const {
    for (int i = 0; i < d->ncon; ++i) {
      const mjContact& c = d->contact[i];
      if (m->geom_bodyid[c.geom1] == m->geom_bodyid[c.geom2]) continue;
      const auto it = allowed.find({c.geom1, c.geom2});
      if (it != allowed.end() && c.dist >= it->second - kBackOutSlack) continue;
      return &c;
    }
    return nullptr;
  }

  // The largest angle by which any joint stands off what its servo commands [rad]: with the
  // gravity feed-forward about 1e-11 at rest; more where something pushes on the arm.
  double PressedOff() const {
    double largest = 0.0;
    for (int k = 0; k < Robots(); ++k) {
      for (int i = 0; i < Joints(k); ++i) {
        largest = std::max(largest, std::abs(d->qpos[qadr[k][i]] - d->ctrl[act[k][i]]));
      }
    }
    return largest;
  }

  std::map<std::pair<int, int>, double> CurrentContacts() const {
    std::map<std::pair<int, int>, double> contacts;
    for (int i = 0; i < d->ncon; ++i) {
      const mjContact& c = d->contact[i];
      const auto key = std::make_pair(c.geom1, c.geom2);
      const auto it = contacts.find(key);
      contacts[key] = it == contacts.end() ? c.dist : std::min(it->second, c.dist);
    }
    return contacts;
  }

  // Link-side minus motor-side angle of robot k's joints now.
  JointVector TransmissionOffset(int k) const {
    JointVector offset = JointVector::Zero(Joints(k));
    for (const auto& e : effects) e->ApplyToTransmission(k, motor[k], direction[k], &offset);
    return offset;
  }

  // Position targets and gravity feed-forward of the robots for the coming step (call after
  // mj_step1, which computed qfrc_bias of the current state).
  void WriteControls() {
    for (int k = 0; k < Robots(); ++k) {
      const JointVector link = motor[k] + TransmissionOffset(k);
      for (int i = 0; i < Joints(k); ++i) {
        d->ctrl[act[k][i]] = link(i);
        const int dof = dadr[k][i];
        d->qfrc_applied[dof] = drives[k][i].gravity_feedforward ? d->qfrc_bias[dof] : 0.0;
      }
    }
  }

  // Largest joint speed of robot `robot`, or of every robot for -1 [rad/s].
  double MaxSpeed(int robot) const {
    double speed = 0.0;
    for (int k = 0; k < Robots(); ++k) {
      if (robot >= 0 && k != robot) continue;
      for (int i = 0; i < Joints(k); ++i) speed = std::max(speed, std::abs(d->qvel[dadr[k][i]]));
    }
    // Compliant target brackets, bearings and bases must come to rest too (each moves with
    // its own robot's motion only, but it is cheap to always include them).
    for (int dof : passive_dofs) speed = std::max(speed, std::abs(d->qvel[dof]));
    return speed;
  }

  // Protective stop: robot `robot`'s joints stop where they are and its motor command holds
  // there, so that a later move can back out of the contact.
  void Halt(int robot) {
    for (int i = 0; i < Joints(robot); ++i) d->qvel[dadr[robot][i]] = 0.0;
    motor[robot] = LinkAngles(robot) - TransmissionOffset(robot);
  }

  // Steps the world: robot `robot`'s motor command ramps to `target` (all joints arriving
  // together at max_joint_speed) and then holds, until it has settled. robot = -1 holds every
  // robot and waits for all.
  MoveResult Run(int robot, const JointVector& target) {
    const PhysicsSpec& ph = spec.physics;
    const double dt = m->opt.timestep;
    JointVector start, delta;
    double ramp_time = 0.0;
    if (robot >= 0) {
      start = motor[robot];
      delta = target - start;
      for (int i = 0; i < Joints(robot); ++i) {
        if (delta(i) != 0.0) direction[robot](i) = delta(i) > 0.0 ? 1.0 : -1.0;
      }
      ramp_time = delta.cwiseAbs().maxCoeff() / ph.max_joint_speed;
    }
    const auto tolerated = CurrentContacts();
    const double t0 = d->time;
    const int warnings = WarningCount(d.get());
    MoveResult result;
    int steps = 0, calm = 0;
    const auto wall0 = std::chrono::steady_clock::now();
    for (;;) {
      if (stop_requested.load(std::memory_order_relaxed)) {
        result.status = MoveStatus::kNotSettled;
        result.reason = "stopped";
        if (robot >= 0) Halt(robot);
        break;
      }
      if (steps >= ph.max_steps) {
        std::ostringstream os;
        os.precision(3);
        os << "still moving after " << steps << " steps (physics.max_steps): largest joint speed "
           << MaxSpeed(robot) << " rad/s, settled below " << ph.settle_speed << " rad/s";
        result.status = MoveStatus::kNotSettled;
        result.reason = os.str();
        break;
      }
      bool ramp_done = true;
      if (robot >= 0) {
        const double t = (steps + 1) * dt;
        ramp_done = t >= ramp_time;
        motor[robot] = ramp_done ? target : JointVector(start + (t / ramp_time) * delta);
      }
      ApplyModelMotion();
      mj_step1(m.get(), d.get());
      if (const mjContact* c = Collision(tolerated)) {
        result.status = MoveStatus::kCollision;
        result.reason = ContactText(*c);
        if (robot >= 0) Halt(robot);
        break;
      }
      WriteControls();
      mj_step2(m.get(), d.get());
      ++steps;
      if (realtime) {
        std::this_thread::sleep_until(wall0 + std::chrono::duration_cast<
                                                  std::chrono::steady_clock::duration>(
                                                  std::chrono::duration<double>(steps * dt)));
      }
      if (WarningCount(d.get()) > warnings) {  // MuJoCo reset the state after a divergence
        result.status = MoveStatus::kNotSettled;
        result.reason = "the simulation diverged (MuJoCo warning); lower physics.stiffness or "
                        "raise physics.armature";
        break;
      }
      calm = ramp_done && MaxSpeed(robot) < ph.settle_speed ? calm + 1 : 0;
      if (calm >= ph.settle_steps) break;
    }
    ApplyModelMotion();
    mj_forward(m.get(), d.get());  // kinematics, cameras and contacts of the final state
    if (result.status == MoveStatus::kSettled) {
      if (const mjContact* c = Collision(tolerated)) {
        result.status = MoveStatus::kCollision;
        result.reason = ContactText(*c);
      } else if (const mjContact* p = Collision({}); p != nullptr && PressedOff() > kPressedOffRad) {
        // A contact the move started in (allowed, so that it can back out) that it came to
        // rest still in, pressing the arm off its commanded angles: a UR5e halted against its
        // own base by a collided move took its next pose 0.45 mrad off at joint 2 while the
        // encoders read the command, a 0.37 mm outlier of a tracker calibration. A real
        // controller's collision detection stops on such a force; a light touch (a board
        // resting on a link, 1e-5 rad) it does not notice, nor does this.
        result.status = MoveStatus::kCollision;
        result.reason = "came to rest pressed against it: " + ContactText(*p);
      }
    }
    result.duration_s = d->time - t0;
    last_steps = steps;
    return result;
  }

  // Throws InputError if a joint's servo would make the Euler step diverge (at the current
  // pose's joint-space inertia, armature included).
  void CheckServoStability(const std::string& where) const {
    const double dt = m->opt.timestep;
    for (int k = 0; k < Robots(); ++k) {
      for (int i = 0; i < Joints(k); ++i) {
        const int dof = dadr[k][i];
        const double inertia = d->qM[m->dof_Madr[dof]];
        const double omega_dt = dt * std::sqrt(drives[k][i].stiffness / inertia);
        if (omega_dt < kMaxOmegaDt) continue;
        std::ostringstream os;
        os.precision(4);
        os << "physics.stiffness: robot " << k << " joint " << i + 1 << " has a drive stiffness of "
           << drives[k][i].stiffness << " N m/rad on an inertia of " << inertia
           << " kg m^2 (armature included): omega * timestep = " << omega_dt
           << " makes the simulation diverge (must stay below " << kMaxOmegaDt
           << "); lower physics.stiffness or physics.timestep_s, or raise physics.armature";
        throw InputError(where, os.str());
      }
    }
  }

  // (Re)builds the MJCF, the MuJoCo model and data and the name lookups from spec and models;
  // the renderers are dropped (their GL context holds the old model).
  void Build() {
    hand_renderer.reset();
    overview_renderer.reset();
    mjcf = WriteTwinMjcf(spec, models, drives, mounts, structures);
    d.reset();
    m = LoadMjcfFromString(mjcf);
    d.reset(mj_makeData(m.get()));
    if (!d) throw std::runtime_error("MuJoCo could not allocate mjData");
    for (int k = 0; k < Robots(); ++k) {
      const std::string p = Prefix(k);
      const int n = Joints(k);
      qadr[k].assign(n, -1);
      dadr[k].assign(n, -1);
      act[k].assign(n, -1);
      site_L[k].assign(n + 2, -1);
      for (int i = 0; i < n; ++i) {
        const int j = Id(mjOBJ_JOINT, p + "j" + std::to_string(i + 1));
        qadr[k][i] = m->jnt_qposadr[j];
        dadr[k][i] = m->jnt_dofadr[j];
        act[k][i] = Id(mjOBJ_ACTUATOR, p + "a" + std::to_string(i + 1));
      }
      for (int i = 0; i <= n + 1; ++i) site_L[k][i] = Id(mjOBJ_SITE, p + "L" + std::to_string(i));
      site_tip[k] = Id(mjOBJ_SITE, p + "tip");
    }
    passive_dofs.clear();
    for (int k = 0; k < Robots(); ++k) {
      std::vector<std::string> names;
      for (const char* axis : {"x", "y", "z"}) names.push_back(std::string("mount_") + axis);
      for (const char* axis : {"x", "y"}) {
        names.push_back(std::string("base_tilt_") + axis);
        for (int i = 0; i < Joints(k); ++i) {
          names.push_back("j" + std::to_string(i + 1) + "_tilt_" + axis);
        }
      }
      for (const std::string& name : names) {
        const int j = mj_name2id(m.get(), mjOBJ_JOINT, (Prefix(k) + name).c_str());
        if (j >= 0) passive_dofs.push_back(m->jnt_dofadr[j]);
      }
      link_body[k].assign(Joints(k), -1);
      link_quat0[k].assign(Joints(k), Eigen::Quaterniond::Identity());
      for (int i = 0; i < Joints(k); ++i) {
        const int b = Id(mjOBJ_BODY, Prefix(k) + "link" + std::to_string(i + 1));
        const mjtNum* quat = m->body_quat + 4 * b;
        link_body[k][i] = b;
        link_quat0[k][i] = Eigen::Quaterniond(quat[0], quat[1], quat[2], quat[3]);
      }
    }
    if (spec.HasCameraAndBoard()) {
      camera = Id(mjOBJ_CAMERA, kHandCameraName);
      board_body = Id(mjOBJ_BODY, Prefix(spec.board.robot) + "board");
    }
    SetUpDrift();
  }

  OffscreenRenderer& HandRenderer() {
    if (!hand_renderer) {
      hand_renderer = std::make_unique<OffscreenRenderer>(m.get(), canvas.width, canvas.height,
                                                          spec.camera.msaa_samples);
      hand_renderer->SetClipPlanes(spec.camera.near_m, spec.camera.far_m);
      hand_renderer->SetSkybox(spec.camera.skybox);
    }
    return *hand_renderer;
  }
};

TwinCell::TwinCell(const TwinSpec& spec, const std::string& where) : impl_(new Impl) {
  Impl& s = *impl_;
  ValidateTwinSpec(spec, where);
  s.spec = spec;
  s.where = where;
  s.effects = MakeEffects(spec);
  std::mt19937_64 geometry_rng = Stream(spec.seed, 0);
  const std::uint64_t noise = spec.noise_seed.value_or(spec.seed);
  s.encoder_rng = Stream(noise, 1);
  s.image_rng = Stream(noise, 2);
  s.operator_rng = Stream(noise, 3);
  s.tracker_rng = Stream(noise, 4);
  s.temperature_rng = Stream(noise, 5);
  for (int k = 0; k < s.Robots(); ++k) {
    s.models[k] = spec.robots[k].model;
    for (const auto& e : s.effects) e->ApplyToGeometry(k, &s.models[k], &geometry_rng);
    s.drives[k].assign(s.models[k].num_joints(), {spec.physics.stiffness, true});
    for (const auto& e : s.effects) e->ApplyToDrive(k, &s.drives[k]);
    for (const auto& e : s.effects) e->ApplyToMount(k, &s.mounts[k]);
    s.structures[k].joint_tilt_stiffness.assign(s.models[k].num_joints(), 0.0);
    for (const auto& e : s.effects) e->ApplyToStructure(k, &s.structures[k]);
    for (const auto& e : s.effects) s.tilts_axes[k] = s.tilts_axes[k] || e->TiltsAxes(k);
  }
  if (spec.HasCameraAndBoard() && spec.camera.distortion.Any()) {
    try {
      s.distortion.emplace(spec.camera.intrinsics, spec.camera.distortion);
    } catch (const std::invalid_argument& e) {
      throw InputError(where, std::string("camera.distortion: ") + e.what());
    }
    s.canvas = s.distortion->canvas();
    // The ideal canvas must stay renderable (plausibility): a lens that needs more than 3 times
    // the image, or 8192 px, per side is not described by this model.
    const Intrinsics& k = spec.camera.intrinsics;
    if (s.canvas.width > std::min(8192, 3 * k.width) ||
        s.canvas.height > std::min(8192, 3 * k.height)) {
      throw InputError(where, "camera.distortion: this lens needs an ideal canvas of " +
                                  std::to_string(s.canvas.width) + " x " +
                                  std::to_string(s.canvas.height) + " px to render a " +
                                  std::to_string(k.width) + " x " + std::to_string(k.height) +
                                  " image; at most 3 times the image and 8192 px per side");
    }
  } else if (spec.HasCameraAndBoard()) {
    s.canvas = spec.camera.intrinsics;
  }
  s.Build();
  // Start at rest at the link-side angles of the initial motor angles.
  for (int k = 0; k < s.Robots(); ++k) {
    s.motor[k] = spec.robots[k].q_initial;
    s.direction[k] = ZeroJoints(s.models[k]);
    const JointVector link = s.motor[k] + s.TransmissionOffset(k);
    for (int i = 0; i < s.Joints(k); ++i) s.d->qpos[s.qadr[k][i]] = link(i);
  }
  s.ApplyModelMotion();
  mj_forward(s.m.get(), s.d.get());
  s.CheckServoStability(where);
  if (const mjContact* c = s.Collision({})) {
    throw InputError(where, "robots[*].q_initial: the initial pose is in collision: " +
                                s.ContactText(*c));
  }
  const MoveResult settle = s.Run(-1, JointVector());
  if (settle.status != MoveStatus::kSettled) {
    throw InputError(where, std::string("robots[*].q_initial: the cell does not settle at its "
                                        "initial pose (") + ToString(settle.status) + "): " +
                                settle.reason);
  }
}

TwinCell::~TwinCell() = default;

MoveResult TwinCell::MoveTo(int robot, const JointVector& q_target) {
  Impl& s = *impl_;
  MoveResult result;
  if (const std::string bad = s.BadRobot(robot); !bad.empty()) {
    result.status = MoveStatus::kInvalidInput;
    result.reason = bad;
    return result;
  }
  if (!q_target.allFinite()) {
    result.status = MoveStatus::kInvalidInput;
    result.reason = "joint targets of robot " + std::to_string(robot) + " are not all finite";
    return result;
  }
  const KinematicModel& model = s.spec.robots[robot].model;
  if (q_target.size() != model.num_joints()) {
    result.status = MoveStatus::kInvalidInput;
    result.reason = "robot " + std::to_string(robot) + " has " +
                    std::to_string(model.num_joints()) + " joints, got " +
                    std::to_string(q_target.size()) + " targets";
    return result;
  }
  for (int i = 0; i < model.num_joints(); ++i) {
    const JointLimits& lim = model.links[i].limits;
    if (q_target(i) < lim.lower || q_target(i) > lim.upper) {
      result.status = MoveStatus::kOutOfLimits;
      result.reason = "robot " + std::to_string(robot) + " joint " + std::to_string(i + 1) +
                      " target " + Deg(q_target(i)) + " deg is outside its limits [" +
                      Deg(lim.lower) + ", " + Deg(lim.upper) + "] deg";
      return result;
    }
  }
  s.stop_requested.store(false);
  return s.Run(robot, q_target);
}

void TwinCell::RequestStop() { impl_->stop_requested.store(true); }

void TwinCell::SetRealtime(bool realtime) { impl_->realtime = realtime; }

// Re-mounts tools while the robots hold still: `change` edits the spec, the world is rebuilt
// with the robots where they stand (link angles, clock and drift carry over), and when the
// rebuilt world has a contact, `change` is applied again (it must undo itself: a swap) so a
// cell never stays in an inconsistent state; then the robots settle under the new payload.
MoveResult TwinCell::RemountTools(const std::function<void()>& change, const std::string& what,
                                  const std::string& refused) {
  Impl& s = *impl_;
  s.stop_requested.store(false);  // a stop request ends only a motion in progress
  std::array<JointVector, kMaxRobots> link;
  for (int k = 0; k < s.Robots(); ++k) link[k] = s.LinkAngles(k);
  const double time = s.d->time;
  const auto rebuild = [&]() {
    change();
    s.Build();
    s.d->time = time;
    for (int k = 0; k < s.Robots(); ++k) {
      for (int i = 0; i < s.Joints(k); ++i) s.d->qpos[s.qadr[k][i]] = link[k](i);
    }
    s.ApplyModelMotion();
    mj_forward(s.m.get(), s.d.get());
  };
  rebuild();
  MoveResult result;
  if (const mjContact* c = s.Collision({})) {
    // The contact lives in the data the rebuild below replaces: its text first.
    const std::string contact = s.ContactText(*c);
    rebuild();
    result.status = MoveStatus::kCollision;
    result.reason = "after " + what + " " + contact + "; " + refused;
    return result;
  }
  return s.Run(-1, JointVector());
}

MoveResult TwinCell::ExchangeTools() {
  Impl& s = *impl_;
  if (!s.spec.HasCameraAndBoard()) {
    MoveResult result;
    result.status = MoveStatus::kInvalidInput;
    result.reason = "this cell has no camera and board to exchange (a one-robot cell)";
    return result;
  }
  // The operator re-mounts both tools on the same brackets while the robots hold still.
  return RemountTools([&s]() { std::swap(s.spec.camera.robot, s.spec.board.robot); },
                      "exchanging the tools",
                      "tools left where they were (move the robots apart first)");
}

MoveResult TwinCell::MountTarget(BracketTarget target) {
  Impl& s = *impl_;
  MoveResult result;
  if (!s.spec.HasCameraAndBoard()) {
    result.status = MoveStatus::kInvalidInput;
    result.reason = "this cell has no board bracket to mount a target on (a one-robot cell)";
    return result;
  }
  if (target == s.mounted) return MoveResult{};
  if (target == BracketTarget::kIntrinsicsTarget && !s.spec.intrinsics_target) {
    result.status = MoveStatus::kInvalidInput;
    result.reason = "this cell has no intrinsics target (the scenario names none)";
    return result;
  }
  if (target != BracketTarget::kFeatureBoard && target != BracketTarget::kIntrinsicsTarget) {
    result.status = MoveStatus::kInvalidInput;
    result.reason = "unknown bracket target " + std::to_string(static_cast<int>(target));
    return result;
  }
  // The plates change places on the board's bracket: spec.board is always what is mounted
  // (the world, the truth and the payload follow it), the other waits in intrinsics_target.
  const auto swap_plates = [&s]() {
    BoardSpec& other = *s.spec.intrinsics_target;
    std::swap(other.robot, s.spec.board.robot);  // the robot stays with the bracket
    std::swap(other, s.spec.board);
  };
  result = RemountTools(swap_plates, std::string("mounting the ") + ToString(target),
                        "the plate left as it was (check the target's size and mount, or "
                        "turn the wrist away from it)");
  if (result.status == MoveStatus::kSettled || result.status == MoveStatus::kNotSettled) {
    s.mounted = target;
  }
  return result;
}

int TwinCell::CameraRobot() {
  impl_->RequireCamera("CameraRobot");
  return impl_->spec.camera.robot;
}

void TwinCell::SetOperatorAlignmentError(double sigma_m) {
  if (!(std::isfinite(sigma_m) && sigma_m >= 0.0)) {
    throw InputError("SetOperatorAlignmentError",
                     "sigma must be a finite number >= 0 m, got " + std::to_string(sigma_m));
  }
  impl_->operator_sigma = sigma_m;
}

double TwinCell::last_contact_gap_m() const { return impl_->last_gap; }

MoveResult TwinCell::JogTipToContact(int j) {
  Impl& s = *impl_;
  MoveResult result;
  s.stop_requested.store(false);  // a stop request ends only a motion in progress
  if (const std::string bad = s.BadRobot(j); !bad.empty()) {
    result.status = MoveStatus::kInvalidInput;
    result.reason = bad;
    return result;
  }
  if (s.Robots() < 2) {
    result.status = MoveStatus::kInvalidInput;
    result.reason = "a handclasp needs two robots; this cell has one (no other tip to touch)";
    return result;
  }
  const int o = 1 - j;
  const std::string who = "handclasp of robot " + std::to_string(j) + " onto robot " +
                          std::to_string(o) + "'s tip: ";
  // The operator sees the true geometry (truth side): the true arm with the tip as its tool.
  const KinematicModel model = TrueTipModel(s.models[j], s.spec.tips[j].X_FTip);
  const Transform X_BW = s.spec.robots[j].X_WB.inverse();
  const Transform X_WTipO = FromMj(s.d->site_xpos + 3 * s.site_tip[o],
                                   s.d->site_xmat + 9 * s.site_tip[o]);
  // Aim point: the other tip plus the operator's alignment error (drawn for every contact, so
  // the stream does not depend on sigma).
  std::normal_distribution<double> normal(0.0, 1.0);
  Vector3 error;
  for (int i = 0; i < 3; ++i) error(i) = normal(s.operator_rng);
  const Vector3 p_W_aim = X_WTipO.translation() + s.operator_sigma * error;
  const Vector3 z_o = X_WTipO.linear().col(2);

  const JointVector q_link = s.LinkAngles(j);
  const auto pose_B = [&](const Matrix3& R_W, const Vector3& p_W) {
    Transform X = Transform::Identity();
    X.linear() = R_W;
    X.translation() = p_W;
    return X_BW * X;
  };
  // Facing orientation and roll: IK solutions, the closest to the current pose first.
  IkOptions ik;
  ik.random_restarts = 8;
  ik.seed = s.spec.seed;
  IkOptions near = ik;
  near.random_restarts = 0;
  struct Candidate {
    double cost;
    JointVector standoff, goal;
    Matrix3 R_W;
  };
  std::vector<Candidate> candidates;
  std::string ik_reason;
  for (int r = 0; r < kHandclaspRolls; ++r) {
    const Matrix3 R_W = FacingRotation(X_WTipO.linear(), 2.0 * kPi * r / kHandclaspRolls);
    const IkResult st =
        SolveIk(model, pose_B(R_W, p_W_aim + kHandclaspStandoff * z_o), q_link, ik);
    if (st.status != IkStatus::kSuccess) {
      ik_reason = st.reason;
      continue;
    }
    const IkResult goal = SolveIk(model, pose_B(R_W, p_W_aim), st.q, near);
    if (goal.status != IkStatus::kSuccess) {
      ik_reason = goal.reason;
      continue;
    }
    candidates.push_back({(st.q - q_link).cwiseAbs().maxCoeff(), st.q, goal.q, R_W});
  }
  if (candidates.empty()) {
    result.status = MoveStatus::kOutOfLimits;
    result.reason = who + "the other tip is out of reach (IK: " + ik_reason + "); nothing moved";
    return result;
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
  // Motor commands for link targets, and one settled move with the limits of MoveTo.
  const auto move = [&](const JointVector& q_link_target, const std::string& stage) {
    const JointVector motor = q_link_target - s.TransmissionOffset(j);
    MoveResult m;
    if (!WithinLimits(s.spec.robots[j].model, motor)) {
      m.status = MoveStatus::kOutOfLimits;
      m.reason = who + stage + ": a joint target is outside the joint limits";
      return m;
    }
    m = s.Run(j, motor);
    result.duration_s += m.duration_s;
    if (m.status != MoveStatus::kSettled) m.reason = who + stage + ": " + m.reason;
    return m;
  };
  // The operator tries the next roll when the way to the stand-off is blocked, backing out to
  // the start pose first.
  const JointVector motor_start = s.motor[j];
  MoveResult m;
  size_t chosen = 0;
  for (; chosen < candidates.size(); ++chosen) {
    m = move(candidates[chosen].standoff, "moving to the stand-off");
    if (m.status == MoveStatus::kSettled) break;
    if (m.status != MoveStatus::kCollision) return m;
    const MoveResult back = s.Run(j, motor_start);
    result.duration_s += back.duration_s;
    if (back.status != MoveStatus::kSettled) {
      m.reason += "; backing out: " + back.reason;
      return m;
    }
  }
  if (chosen == candidates.size()) {
    m.reason += " (every one of " + std::to_string(candidates.size()) + " tip rolls blocked)";
    return m;
  }
  const Candidate& best = candidates[chosen];
  const Matrix3 R_W_goal = best.R_W;
  // Straight approach along the other tip's axis.
  JointVector q = best.standoff;
  for (int k = 1; k <= kApproachWaypoints; ++k) {
    const double back = kHandclaspStandoff * (1.0 - static_cast<double>(k) / kApproachWaypoints);
    const IkResult step = SolveIk(model, pose_B(R_W_goal, p_W_aim + back * z_o), q, near);
    if (step.status != IkStatus::kSuccess) {
      m.status = MoveStatus::kOutOfLimits;
      m.reason = who + "approach: " + step.reason;
      return m;
    }
    q = step.q;
    m = move(q, "approaching");
    if (m.status != MoveStatus::kSettled) return m;
  }
  // Corrective jogs on what the operator sees (true site positions), by the true Jacobian.
  const Transform X_BW_inv = X_BW;
  for (int jog = 0;; ++jog) {
    const Vector3 p_W = Vector3(s.d->site_xpos + 3 * s.site_tip[j]);
    const Vector3 gap_W = p_W_aim - p_W;
    if (gap_W.norm() <= kContactToleranceM) {
      s.last_gap = gap_W.norm();
      result.status = MoveStatus::kSettled;
      return result;
    }
    if (jog >= kMaxCorrectiveJogs) {
      std::ostringstream os;
      os << who << "the tips are still " << gap_W.norm() * 1e3 << " mm from contact after "
         << kMaxCorrectiveJogs << " corrective jogs";
      result.status = MoveStatus::kNotSettled;
      result.reason = os.str();
      return result;
    }
    const JointVector q_now = s.LinkAngles(j);
    const Matrix3 R_W_now = FromMj(s.d->site_xpos + 3 * s.site_tip[j],
                                   s.d->site_xmat + 9 * s.site_tip[j]).linear();
    Eigen::Matrix<double, 6, 1> twist;
    twist.head<3>() = X_BW_inv.linear() * gap_W;
    const Eigen::AngleAxisd w(R_W_goal * R_W_now.transpose());
    twist.tail<3>() = X_BW_inv.linear() * (w.angle() * w.axis());
    const JointVector dq =
        ManipulatorJacobian(model, q_now).colPivHouseholderQr().solve(twist);
    // The jog is relative to the current command (what the operator's pendant holds).
    m = move(s.motor[j] + s.TransmissionOffset(j) + dq, "jogging");
    if (m.status != MoveStatus::kSettled) return m;
  }
}

JointVector TwinCell::ReadEncoders(int robot) {
  Impl& s = *impl_;
  if (const std::string bad = s.BadRobot(robot); !bad.empty()) {
    throw InputError("ReadEncoders", bad);
  }
  JointVector reading = s.motor[robot];
  for (const auto& e : s.effects) e->ApplyToEncoder(robot, &reading, &s.encoder_rng);
  return reading;
}

cv::Mat TwinCell::GrabImage() {
  Impl& s = *impl_;
  s.RequireCamera("GrabImage");
  cv::Mat image = s.HandRenderer().RenderPinhole(s.m.get(), s.d.get(), s.camera, s.canvas);
  if (s.distortion) image = s.distortion->Apply(image);
  for (const auto& e : s.effects) e->ApplyToImage(&image, &s.image_rng);
  return image;
}

cv::Mat TwinCell::GrabImageRegion(const cv::Rect& roi) {
  Impl& s = *impl_;
  s.RequireCamera("GrabImageRegion");
  const Intrinsics& K = s.spec.camera.intrinsics;
  const cv::Rect r = roi & cv::Rect(0, 0, K.width, K.height);
  if (r.empty()) return cv::Mat();
  if (r.width == K.width && r.height == K.height) return GrabImage();
  const cv::Rect canvas_region = s.distortion ? s.distortion->CanvasRegion(r) : r;
  cv::Mat image =
      s.HandRenderer().RenderPinholeRegion(s.m.get(), s.d.get(), s.camera, s.canvas, canvas_region);
  if (s.distortion) image = s.distortion->ApplyRegion(image, canvas_region, r);
  for (const auto& e : s.effects) e->ApplyToImage(&image, &s.image_rng);
  return image;
}

double TwinCell::ClockSeconds() { return impl_->d->time; }

double TwinCell::ReadTemperatureC(int robot) {
  Impl& s = *impl_;
  if (const std::string bad = s.BadRobot(robot); !bad.empty()) {
    throw InputError("ReadTemperatureC", bad);
  }
  const TemperatureSensorSpec& sensor = s.spec.robots[robot].temperature_sensor;
  if (!sensor.present) return std::numeric_limits<double>::quiet_NaN();
  double t = sensor.ambient_C;
  for (const auto& e : s.effects) t += e->TemperatureDeltaAt(robot, s.d->time);
  std::normal_distribution<double> noise(0.0, 1.0);
  return t + sensor.sigma_K * noise(s.temperature_rng);
}

TrackerReading TwinCell::MeasureTracker(int robot) {
  Impl& s = *impl_;
  const TrackerSpec& t = s.spec.tracker;
  TrackerReading r;
  r.time_s = s.d->time;
  if (!t.present || robot != t.robot) {
    r.status = TrackerStatus::kNoTracker;
    r.reason = t.present ? "the tracker's reflector is on robot " + std::to_string(t.robot + 1) +
                               ", not on robot " + std::to_string(robot + 1)
                         : "this cell has no laser tracker";
    return r;
  }
  const int flange_site = s.site_L[robot][s.Joints(robot)];
  const Transform X_WF = FromMj(s.d->site_xpos + 3 * flange_site, s.d->site_xmat + 9 * flange_site);
  const Vector3 p_W = X_WF * t.p_FR;
  const Vector3 origin = t.X_WT.translation();
  const Vector3 ray = p_W - origin;
  const double range = ray.norm();
  if (range > t.max_range_m) {
    r.status = TrackerStatus::kOutOfRange;
    r.reason = "the reflector is " + std::to_string(range) + " m from the tracker, beyond its " +
               std::to_string(t.max_range_m) + " m";
    return r;
  }
  // Line of sight: the first geom along the beam, the reflector's own flange body excepted.
  const mjtNum pnt[3] = {origin.x(), origin.y(), origin.z()};
  const mjtNum vec[3] = {ray.x() / range, ray.y() / range, ray.z() / range};
  int geom = -1;
  const int flange_body = s.m->site_bodyid[flange_site];
  const mjtNum hit = mj_ray(s.m.get(), s.d.get(), pnt, vec, nullptr, 1, flange_body, &geom);
  if (geom >= 0 && hit >= 0 && hit < range - 1e-6) {
    r.status = TrackerStatus::kOccluded;
    r.reason = "the beam to the reflector is blocked by " + s.BodyName(geom) + " " +
               std::to_string(hit) + " m from the tracker";
    return r;
  }
  std::normal_distribution<double> noise(0.0, 1.0);
  const double sigma = t.sigma_m + t.sigma_per_m * range;
  Vector3 p_T = t.X_WT.inverse() * p_W + t.drift_m_per_s * s.d->time;
  for (int k = 0; k < 3; ++k) p_T(k) += sigma * noise(s.tracker_rng);
  r.status = TrackerStatus::kOk;
  r.p_T = p_T;
  return r;
}

TwinTruth TwinCell::Truth() const {
  const Impl& s = *impl_;
  TwinTruth t;
  t.num_robots = s.Robots();
  t.models = s.models;
  t.time_s = s.d->time;
  t.camera = s.spec.camera;
  t.board = s.spec.board;
  t.tracker = s.spec.tracker;
  for (int k = 0; k < s.Robots(); ++k) {
    t.X_WB[k] = s.spec.robots[k].X_WB;
    t.length_scale[k] = s.LengthScale(k, s.d->time);
    t.q_link[k] = s.LinkAngles(k);
    t.q_motor[k] = s.motor[k];
    t.p_WTip[k] = Vector3(s.d->site_xpos + 3 * s.site_tip[k]);
    const int flange = s.site_L[k][s.Joints(k)];
    t.X_WF[k] = FromMj(s.d->site_xpos + 3 * flange, s.d->site_xmat + 9 * flange);
    t.X_FTip[k] = s.spec.tips[k].X_FTip;
  }
  if (!s.spec.HasCameraAndBoard()) return t;
  // MuJoCo's camera looks along -z with y up; the optical frame C is it turned by pi about x.
  t.X_WC = FromMj(s.d->cam_xpos + 3 * s.camera, s.d->cam_xmat + 9 * s.camera) *
           Transform(Eigen::AngleAxisd(kPi, Vector3::UnitX()));
  t.X_WT = FromMj(s.d->xpos + 3 * s.board_body, s.d->xmat + 9 * s.board_body);
  return t;
}

const std::string& TwinCell::mjcf() const { return impl_->mjcf; }

cv::Mat TwinCell::RenderOverview(int width, int height, double azimuth_deg,
                                 double elevation_deg) {
  Impl& s = *impl_;
  if (width < 1 || width > kMaxOverviewWidth || height < 1 || height > kMaxOverviewHeight) {
    throw InputError("RenderOverview", "size " + std::to_string(width) + "x" +
                                           std::to_string(height) + " px must be within 1x1 to " +
                                           std::to_string(kMaxOverviewWidth) + "x" +
                                           std::to_string(kMaxOverviewHeight));
  }
  if (!s.overview_renderer || s.overview_renderer->width() != width ||
      s.overview_renderer->height() != height) {
    s.overview_renderer.reset();  // one context at a time
    // The MJCF's samples: the hand camera's, or the default of a cell without one.
    s.overview_renderer = std::make_unique<OffscreenRenderer>(s.m.get(), width, height,
                                                              s.m->vis.quality.offsamples);
  }
  // Both bases in view, 1.4 times their distance back; one arm: its stretched length.
  const Vector3 b0 = s.spec.robots[0].X_WB.translation();
  const Vector3 b1 = s.spec.robots[s.Robots() - 1].X_WB.translation();
  const Vector3 lookat = 0.5 * (b0 + b1) + Vector3(0, 0, 0.35);
  double spread = (b1 - b0).norm();
  if (s.Robots() == 1) {
    spread = 0.0;
    for (const Link& link : s.models[0].links) spread += std::hypot(link.dh.a, link.dh.d);
  }
  mjvCamera cam;
  mjv_defaultCamera(&cam);
  cam.type = mjCAMERA_FREE;
  for (int i = 0; i < 3; ++i) cam.lookat[i] = lookat(i);
  cam.distance = 1.0 + 1.4 * spread;
  cam.azimuth = azimuth_deg;
  cam.elevation = elevation_deg;
  return s.overview_renderer->RenderFree(s.m.get(), s.d.get(), cam);
}

std::vector<Transform> TwinCell::SiteFrames(int robot) const {
  const Impl& s = *impl_;
  if (const std::string bad = s.BadRobot(robot); !bad.empty()) {
    throw InputError("SiteFrames", bad);
  }
  std::vector<Transform> frames(s.site_L[robot].size());
  for (size_t i = 0; i < frames.size(); ++i) {
    const int site = s.site_L[robot][i];
    frames[i] = FromMj(s.d->site_xpos + 3 * site, s.d->site_xmat + 9 * site);
  }
  return frames;
}

int TwinCell::last_move_steps() const { return impl_->last_steps; }

void TwinCell::RenderBare() {
  Impl& s = *impl_;
  s.RequireCamera("RenderBare");
  s.HandRenderer().RenderBare(s.m.get(), s.d.get(), s.camera);
}

}  // namespace twin
