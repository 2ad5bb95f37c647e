#include "bench/io/urdf_model.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <optional>
#include <sstream>
#include <vector>

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include "bench/io/plausibility.h"
#include "bench/io/yaml_util.h"
#include "calib/common/text_format.h"
#include "bench/io/output_files.h"
#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "sim/world/mjcf_writer.h"

namespace twin {
namespace {

// Below this sine of the angle between consecutive joint axes the link uses the Hayati form
// (d = 0 plus beta): classic DH would put the common normal up to offset / sine metres away.
constexpr double kNearParallelSine = 1e-2;
// Parallel axes closer than this turn about one line: the link is undefined [m].
constexpr double kCoincidentDistance = 1e-9;
// A base axis whose part perpendicular to z0 is shorter than this is not used as x0.
constexpr double kMinProjection = 0.1;
// Travel given to continuous joints [rad].
constexpr double kContinuousTravel = 2.0 * kPi;

using JointPtr = urdf::JointConstSharedPtr;

// A joint axis line at q = 0: a point on it and its unit direction.
struct AxisLine {
  Vector3 point;
  Vector3 dir;
};

Transform ToTransform(const urdf::Pose& pose) {
  const urdf::Rotation& r = pose.rotation;
  Transform X = Transform::Identity();
  X.linear() = Eigen::Quaterniond(r.w, r.x, r.y, r.z).normalized().toRotationMatrix();
  X.translation() << pose.position.x, pose.position.y, pose.position.z;
  return X;
}

Matrix3 RotZ(double angle) { return Eigen::AngleAxisd(angle, Vector3::UnitZ()).matrix(); }

std::string TypeName(int type) {
  switch (type) {
    case urdf::Joint::REVOLUTE: return "revolute";
    case urdf::Joint::CONTINUOUS: return "continuous";
    case urdf::Joint::PRISMATIC: return "prismatic";
    case urdf::Joint::FLOATING: return "floating";
    case urdf::Joint::PLANAR: return "planar";
    case urdf::Joint::FIXED: return "fixed";
    default: return "unknown";
  }
}

bool IsRevolute(const urdf::Joint& j) {
  return j.type == urdf::Joint::REVOLUTE || j.type == urdf::Joint::CONTINUOUS;
}

std::string ListNames(const std::vector<std::string>& names) {
  std::string s = "[";
  for (size_t i = 0; i < names.size(); ++i) s += (i ? ", " : "") + names[i];
  return s + "]";
}

// ---- Parsing and the chain ------------------------------------------------------------------

// Largest URDF read [bytes]: URDFs reference their meshes, so even a robot with many links
// and collision shapes is well below 1 MiB; 16 MiB keeps a wrong path from filling memory.
constexpr std::uintmax_t kMaxUrdfBytes = std::uintmax_t{16} << 20;

// Collects urdfdom's messages, which it prints through console_bridge (its reasons for
// refusing a file, or for silently dropping an element it could not read), while it parses.
class UrdfdomMessages : public console_bridge::OutputHandler {
 public:
  UrdfdomMessages() : previous_(console_bridge::getOutputHandler()) {
    console_bridge::useOutputHandler(this);
  }
  ~UrdfdomMessages() override { console_bridge::useOutputHandler(previous_); }
  UrdfdomMessages(const UrdfdomMessages&) = delete;
  UrdfdomMessages& operator=(const UrdfdomMessages&) = delete;

  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) errors_.push_back(text);
  }
  const std::vector<std::string>& errors() const { return errors_; }

 private:
  console_bridge::OutputHandler* previous_;
  std::vector<std::string> errors_;
};

// 1-based line of the first `<element ... name="name"` in the text, or 0.
int ElementLine(const std::string& text, const std::string& element, const std::string& name) {
  const std::string open = "<" + element;
  for (std::size_t at = text.find(open); at != std::string::npos; at = text.find(open, at + 1)) {
    const std::size_t after = at + open.size();
    if (after >= text.size() || !std::isspace(static_cast<unsigned char>(text[after]))) continue;
    const std::size_t close = text.find('>', after);
    const std::string tag = text.substr(after, close == std::string::npos ? std::string::npos
                                                                          : close - after);
    for (std::size_t n = tag.find("name"); n != std::string::npos; n = tag.find("name", n + 1)) {
      if (n > 0 && !std::isspace(static_cast<unsigned char>(tag[n - 1]))) continue;
      std::size_t k = n + 4;
      while (k < tag.size() && std::isspace(static_cast<unsigned char>(tag[k]))) ++k;
      if (k >= tag.size() || tag[k] != '=') continue;
      ++k;
      while (k < tag.size() && std::isspace(static_cast<unsigned char>(tag[k]))) ++k;
      if (k >= tag.size() || (tag[k] != '"' && tag[k] != '\'')) continue;
      const std::size_t end = tag.find(tag[k], k + 1);
      if (end != std::string::npos && tag.compare(k + 1, end - k - 1, name) == 0) {
        return 1 + static_cast<int>(std::count(text.begin(), text.begin() + at, '\n'));
      }
    }
  }
  return 0;
}

// "source:line" of an element (just "source" when it cannot be found).
std::string ElementWhere(const std::string& text, const std::string& source,
                         const std::string& element, const std::string& name) {
  const int line = ElementLine(text, element, name);
  return line > 0 ? source + ":" + std::to_string(line) : source;
}

// Where urdfdom's messages point: the first link or joint they name ("... for Link [a]",
// "Joint [j] is ..."), else the file.
std::string MessageWhere(const std::string& text, const std::string& source,
                         const std::vector<std::string>& messages) {
  for (const std::string& message : messages) {
    std::string lower = message;
    std::transform(lower.begin(), lower.end(), lower.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    for (const std::string element : {"link", "joint"}) {
      const std::size_t at = lower.find(element + " [");
      if (at == std::string::npos) continue;
      const std::size_t begin = at + element.size() + 2;
      const std::size_t end = message.find(']', begin);
      if (end == std::string::npos) continue;
      return ElementWhere(text, source, element, message.substr(begin, end - begin));
    }
  }
  return source;
}

urdf::ModelInterfaceSharedPtr ParseText(const std::string& text, const std::string& source) {
  urdf::ModelInterfaceSharedPtr urdf;
  UrdfdomMessages messages;
  try {
    urdf = urdf::parseURDF(text);
  } catch (const std::exception& e) {
    throw InputError(source, std::string("not a valid URDF: ") + e.what());
  }
  // urdfdom reports some bad values (a mass that is not a number) and then goes on without
  // the element: any error it reports refuses the file, with its own words.
  if (!messages.errors().empty()) {
    std::string why;
    for (const std::string& e : messages.errors()) why += (why.empty() ? "" : "; ") + e;
    throw InputError(MessageWhere(text, source, messages.errors()),
                     "not a valid URDF: urdfdom: " + why);
  }
  if (!urdf) {
    throw InputError(source, "not a valid URDF: urdfdom rejected it without a reason (malformed "
                             "XML, no <robot name=...>, or links that do not form one tree)");
  }
  return urdf;
}

// Plausibility of every link and joint of the file (bench/io/plausibility.h), before the chain
// is built: masses (urdfdom accepts negative and NaN ones), inertias, origins and limits.
void CheckPlausible(const urdf::ModelInterface& urdf, const std::string& text,
                    const std::string& source) {
  const auto fail = [&](const std::string& element, const std::string& name,
                        const std::string& key, const std::string& problem) {
    throw InputError(ElementWhere(text, source, element, name) + " " + element + " '" + name +
                         "' " + key,
                     problem);
  };
  const auto position = [&](const std::string& element, const std::string& name,
                            const std::string& key, const urdf::Vector3& p) {
    for (double v : {p.x, p.y, p.z}) {
      if (const auto problem = plausibility::LengthProblem(v)) fail(element, name, key, *problem);
    }
  };
  for (const auto& [name, link] : urdf.links_) {
    if (!link || !link->inertial) continue;
    const urdf::Inertial& in = *link->inertial;
    if (const auto p = plausibility::MassProblem(in.mass)) fail("link", name, "<mass value>", *p);
    Matrix3 I;
    I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
    if (const auto p = plausibility::InertiaProblem(in.mass, I)) fail("link", name, "<inertia>", *p);
    position("link", name, "<inertial><origin xyz>", in.origin.position);
  }
  for (const auto& [name, joint] : urdf.joints_) {
    if (!joint) continue;
    position("joint", name, "<origin xyz>", joint->parent_to_joint_origin_transform.position);
    if (joint->type == urdf::Joint::REVOLUTE && joint->limits) {
      for (double v : {joint->limits->lower, joint->limits->upper}) {
        if (const auto p = plausibility::JointLimitProblem(v, "rad", 1.0)) {
          fail("joint", name, "<limit>", *p);
        }
      }
    }
  }
}

urdf::LinkConstSharedPtr RequireLink(const urdf::ModelInterface& urdf, const std::string& name,
                                     const std::string& role, const std::string& source) {
  urdf::LinkConstSharedPtr link = urdf.getLink(name);
  if (!link) throw InputError(source, role + " '" + name + "' is not a link of the URDF");
  return link;
}

void CollectLeaves(const urdf::Link& link, std::vector<std::string>* leaves) {
  if (link.child_links.empty()) leaves->push_back(link.name);
  for (const auto& child : link.child_links) CollectLeaves(*child, leaves);
}

// Moving (non-fixed) joints between `base` and its descendant `leaf`.
int MovingJointsAbove(const urdf::ModelInterface& urdf, const std::string& base,
                      const std::string& leaf) {
  int n = 0;
  for (urdf::LinkConstSharedPtr link = urdf.getLink(leaf); link && link->name != base &&
                                                           link->parent_joint;
       link = urdf.getLink(link->parent_joint->parent_link_name)) {
    if (link->parent_joint->type != urdf::Joint::FIXED) ++n;
  }
  return n;
}

// The end of the arm when no tip_link is given: the only leaf below base_link, or else the one
// leaf with the most moving joints above it. Frames hung on fixed joints nearer the base (the
// ROS-Industrial `base` frame beside `base_link`, a sensor on the forearm) are passed over,
// with a warning naming them; a tie is refused.
std::string DefaultTip(const urdf::ModelInterface& urdf, const urdf::Link& base,
                       const std::string& source, std::vector<std::string>* warnings) {
  std::vector<std::string> leaves;
  CollectLeaves(base, &leaves);
  if (leaves.size() == 1 && leaves[0] != base.name) return leaves[0];
  if (leaves.size() == 1) throw InputError(source, "base_link '" + base.name + "' has no children");
  std::vector<int> moving(leaves.size());
  for (size_t k = 0; k < leaves.size(); ++k) {
    moving[k] = MovingJointsAbove(urdf, base.name, leaves[k]);
  }
  const int most = *std::max_element(moving.begin(), moving.end());
  std::vector<std::string> best, others;
  for (size_t k = 0; k < leaves.size(); ++k) {
    (moving[k] == most ? best : others)
        .push_back(leaves[k] + " (" + std::to_string(moving[k]) + " moving joints)");
  }
  if (best.size() != 1) {
    throw InputError(source, "the URDF has several leaf links " + ListNames(leaves) + ", " +
                                 std::to_string(best.size()) + " of them " +
                                 std::to_string(most) + " moving joints below base_link '" +
                                 base.name + "'; pass tip_link to choose the end of the arm");
  }
  const std::string tip = best[0].substr(0, best[0].find(" ("));
  if (warnings) {
    warnings->push_back(source + ": tip_link not given: chose '" + tip + "', the leaf link with "
                        "the most moving joints below base_link '" + base.name +
                        "'; passed over " + ListNames(others) + " (pass tip_link to choose)");
  }
  return tip;
}

// All joints from base to tip (fixed ones included), base first.
std::vector<JointPtr> JointsBetween(const urdf::ModelInterface& urdf, const std::string& base,
                                    const std::string& tip, const std::string& source) {
  std::vector<JointPtr> joints;
  for (urdf::LinkConstSharedPtr link = urdf.getLink(tip); link->name != base;
       link = urdf.getLink(joints.back()->parent_link_name)) {
    if (!link->parent_joint) {
      throw InputError(source, "tip_link '" + tip + "' is not below base_link '" + base + "'");
    }
    joints.push_back(link->parent_joint);
  }
  std::reverse(joints.begin(), joints.end());
  return joints;
}

// The six moving joints of the chain, base first; anything but revolute, continuous and
// fixed joints, or another count, is an error.
std::vector<JointPtr> MovingJoints(const std::vector<JointPtr>& chain, const std::string& base,
                                   const std::string& tip, const std::string& source) {
  std::vector<JointPtr> moving;
  std::vector<std::string> names;
  for (const JointPtr& j : chain) {
    if (j->type == urdf::Joint::FIXED) continue;
    if (!IsRevolute(*j)) {
      throw InputError(source, "joint '" + j->name + "' is " + TypeName(j->type) +
                                   "; only revolute, continuous and fixed joints are supported");
    }
    moving.push_back(j);
    names.push_back(j->name);
  }
  if (moving.empty() || moving.size() > static_cast<std::size_t>(kMaxJoints)) {
    throw InputError(source, "expected 1 to " + std::to_string(kMaxJoints) +
                                 " revolute joints between '" + base + "' and '" + tip +
                                 "', found " + std::to_string(moving.size()) + ": " +
                                 ListNames(names));
  }
  return moving;
}

JointLimits LimitsOf(const urdf::Joint& j, const std::string& source) {
  if (j.type == urdf::Joint::CONTINUOUS) return {-kContinuousTravel, kContinuousTravel};
  if (!j.limits) throw InputError(source, "revolute joint '" + j.name + "' has no <limit>");
  if (!(j.limits->lower < j.limits->upper)) {
    std::ostringstream os;
    os << "joint '" << j.name << "': lower limit " << j.limits->lower
       << " rad must be below upper limit " << j.limits->upper << " rad";
    throw InputError(source, os.str());
  }
  return {j.limits->lower, j.limits->upper};
}

// Walks the chain at q = 0: axis lines of the moving joints in B; returns the tip pose X_BT.
Transform ChainAtZero(const std::vector<JointPtr>& chain, const std::string& source,
                      std::vector<AxisLine>* axes) {
  Transform X_BC = Transform::Identity();
  for (const JointPtr& j : chain) {
    X_BC = X_BC * ToTransform(j->parent_to_joint_origin_transform);
    if (!IsRevolute(*j)) continue;
    const Vector3 axis(j->axis.x, j->axis.y, j->axis.z);
    if (!(axis.norm() > 1e-12) || !axis.allFinite()) {
      throw InputError(source, "joint '" + j->name + "' has a zero axis vector");
    }
    axes->push_back({X_BC.translation(), X_BC.linear() * axis.normalized()});
  }
  return X_BC;
}

// ---- DH frames from axis lines --------------------------------------------------------------

// L0: z along axis 1, origin at the point of axis 1 nearest B's origin, x0 along B's x axis
// (B's y axis if x is nearly along z0) made perpendicular to z0.
Transform BaseToL0(const AxisLine& axis1) {
  const Vector3 z = axis1.dir;
  Vector3 x = Vector3::UnitX() - z.x() * z;
  if (x.norm() < kMinProjection) x = Vector3::UnitY() - z.y() * z;
  x.normalize();
  const Vector3 y = z.cross(x);
  Transform X = Transform::Identity();
  X.linear() << y.cross(z), y, z;
  X.translation() = axis1.point - axis1.point.dot(z) * z;
  return X;
}

// Classic DH to the skew or intersecting axis (p, u) given in L(i-1): x_i along z x u.
DhParameters ClassicDh(const Vector3& p, const Vector3& u) {
  const double sine = std::hypot(u.x(), u.y());
  const Vector3 n(-u.y() / sine, u.x() / sine, 0.0);
  // Foot of the common normal on z_(i-1): s with (0,0,s) + a n = p + t u.
  const double b = u.z(), e = -u.dot(p), d0 = -p.z();
  const double s = (b * e - d0) / (sine * sine);
  DhParameters dh;
  dh.theta_offset = std::atan2(n.y(), n.x());
  dh.d = s;
  dh.a = p.dot(n);
  dh.alpha = std::atan2(sine, u.z());
  return dh;
}

// Hayati form (d = 0) to the nearly parallel axis (p, u) given in L(i-1): the common normal
// lies in the plane z = 0 of L(i-1). Returns false if the axes are coincident.
bool HayatiDh(const Vector3& p, const Vector3& u, DhParameters* dh) {
  const Vector3 c = p - (p.z() / u.z()) * u;  // axis i+1 meets the plane z = 0
  const double a = std::hypot(c.x(), c.y());
  if (a < kCoincidentDistance) return false;
  dh->theta_offset = std::atan2(c.y(), c.x());
  dh->d = 0.0;
  dh->a = a;
  const Vector3 v = RotZ(-dh->theta_offset) * u;  // = RotX(alpha) RotY(beta) e_z
  dh->alpha = std::atan2(-v.y(), v.z());
  dh->beta = std::atan2(v.x(), std::hypot(v.y(), v.z()));
  return true;
}

// Link 6: a pure RotZ TransZ along axis 6 placing L6 at the foot of the tip on axis 6, x6 along
// the tip's x axis (or its y axis turned back by 90 deg) projected onto the xy plane of L5.
DhParameters FlangeDh(const Transform& X_L5T) {
  const Matrix3& R = X_L5T.linear();
  DhParameters dh;
  dh.d = X_L5T.translation().z();
  if (std::hypot(R(0, 0), R(1, 0)) >= kMinProjection) {
    dh.theta_offset = std::atan2(R(1, 0), R(0, 0));
  } else {
    dh.theta_offset = std::remainder(std::atan2(R(1, 1), R(0, 1)) - kPi / 2, 2 * kPi);
  }
  return dh;
}

void BuildGeometry(const std::vector<AxisLine>& axes, const Transform& X_BT,
                   const std::vector<JointPtr>& moving, const std::string& source,
                   KinematicModel* model) {
  model->X_BL0 = BaseToL0(axes[0]);
  Transform X_BL = model->X_BL0;
  const int n = model->num_joints();
  for (int i = 0; i + 1 < n; ++i) {
    const Vector3 p = X_BL.inverse() * axes[i + 1].point;
    const Vector3 u = X_BL.linear().transpose() * axes[i + 1].dir;
    DhParameters& dh = model->links[i].dh;
    if (std::hypot(u.x(), u.y()) >= kNearParallelSine) {
      dh = ClassicDh(p, u);
    } else if (!HayatiDh(p, u, &dh)) {
      throw InputError(source, "joints '" + moving[i]->name + "' and '" + moving[i + 1]->name +
                                   "' turn about the same line (coincident axes)");
    }
    X_BL = X_BL * LinkTransform(dh, 0.0);
  }
  model->links[n - 1].dh = FlangeDh(X_BL.inverse() * X_BT);
  X_BL = X_BL * LinkTransform(model->links[n - 1].dh, 0.0);  // L_N = L_t
  model->X_LtE = X_BL.inverse() * X_BT;
}

// ---- Mass properties ------------------------------------------------------------------------

// Mass, first and second moments about the origin of a body's DH frame, in that frame.
struct MassSums {
  double mass = 0.0;
  Vector3 first = Vector3::Zero();
  Matrix3 second = Matrix3::Zero();

  void Add(const urdf::Inertial& in, const Transform& X_LI) {
    Matrix3 I;
    I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
    const Matrix3& R = X_LI.linear();
    const Vector3 c = X_LI.translation();
    mass += in.mass;
    first += in.mass * c;
    second += R * I * R.transpose() +
              in.mass * (c.squaredNorm() * Matrix3::Identity() - c * c.transpose());
  }

  LinkInertia ToInertia() const {
    LinkInertia out;
    if (!(mass > 0.0)) return out;
    out.mass = mass;
    out.p_LiCom = first / mass;
    const Vector3& c = out.p_LiCom;
    const Matrix3 I = second - mass * (c.squaredNorm() * Matrix3::Identity() - c * c.transpose());
    out.I_Com = 0.5 * (I + I.transpose());
    return out;
  }
};

// Assigns every link below the base to the body it rides on at q = 0: a chain joint starts
// body k (DH frame L(k+1)); any other joint, fixed or off-chain, keeps its parent's body.
class MassCollector {
 public:
  MassCollector(const urdf::ModelInterface& urdf, const std::vector<JointPtr>& moving,
                const FrameSet& frames)
      : urdf_(urdf), frames_(frames) {
    for (size_t k = 0; k < moving.size(); ++k) body_of_joint_[moving[k]->name] = int(k);
    sums_.resize(moving.size());
  }

  void Visit(const urdf::Link& link, const Transform& X_B_link, int body) {
    if (body >= 0 && link.inertial) {
      const Transform& X_BL = frames_.X_BL[body + 1];
      const Transform X_B_inertial = X_B_link * ToTransform(link.inertial->origin);
      sums_[body].Add(*link.inertial, X_BL.inverse() * X_B_inertial);
    }
    for (const auto& joint : link.child_joints) {
      const auto it = body_of_joint_.find(joint->name);
      const int child_body = it == body_of_joint_.end() ? body : it->second;
      const Transform X_B_child = X_B_link * ToTransform(joint->parent_to_joint_origin_transform);
      Visit(*urdf_.getLink(joint->child_link_name), X_B_child, child_body);
    }
  }

  LinkInertia Inertia(int body) const { return sums_[body].ToInertia(); }

 private:
  const urdf::ModelInterface& urdf_;
  const FrameSet& frames_;
  std::map<std::string, int> body_of_joint_;
  std::vector<MassSums> sums_;
};

void AssignInertias(const urdf::ModelInterface& urdf, const urdf::Link& base,
                    const std::vector<JointPtr>& moving, KinematicModel* model) {
  const FrameSet frames = ForwardKinematics(*model, ZeroJoints(*model));
  MassCollector collector(urdf, moving, frames);
  collector.Visit(base, Transform::Identity(), -1);
  for (int k = 0; k < model->num_joints(); ++k) model->links[k].inertia = collector.Inertia(k);
  model->tool().inertia = LinkInertia{};
}

// ---- Warnings -------------------------------------------------------------------------------

bool IsFile(const std::filesystem::path& p) {
  std::error_code ec;
  return std::filesystem::is_regular_file(p, ec);
}

// Whether a mesh file name of the URDF names a file on this machine: package://pkg/rest under
// a folder of ROS_PACKAGE_PATH (pkg itself or a folder holding it) or of AMENT_PREFIX_PATH
// (share/pkg), file:// and plain paths as they are or relative to the URDF's folder.
bool MeshResolves(const std::string& filename, const std::filesystem::path& urdf_dir) {
  namespace fs = std::filesystem;
  const std::string package = "package://", file = "file://";
  if (filename.rfind(package, 0) == 0) {
    const std::string rest = filename.substr(package.size());
    const std::size_t slash = rest.find('/');
    if (slash == std::string::npos) return false;
    const std::string pkg = rest.substr(0, slash), inside = rest.substr(slash + 1);
    for (const char* var : {"ROS_PACKAGE_PATH", "AMENT_PREFIX_PATH"}) {
      const char* value = std::getenv(var);
      if (!value) continue;
      std::stringstream folders(value);
      for (std::string folder; std::getline(folders, folder, ':');) {
        if (folder.empty()) continue;
        const fs::path f(folder);
        if (IsFile(f / pkg / inside) || IsFile(f / "share" / pkg / inside) ||
            (f.filename() == pkg && IsFile(f / inside))) {
          return true;
        }
      }
    }
    return false;
  }
  const fs::path path(filename.rfind(file, 0) == 0 ? filename.substr(file.size()) : filename);
  return IsFile(path) || (path.is_relative() && IsFile(urdf_dir / path));
}

// Warns about the meshes of the links below base_link that cannot be found (the twin never
// loads meshes: it draws capsules along the links, so the rendered arm and its collisions are
// capsules either way; an unresolved mesh also means the user's visual model is not here).
void WarnMeshes(const urdf::Link& base, const std::string& source,
                std::vector<std::string>* warnings) {
  std::vector<std::string> unresolved;
  int meshes = 0;
  const std::filesystem::path dir = std::filesystem::path(source).parent_path();
  std::vector<const urdf::Link*> stack = {&base};
  while (!stack.empty()) {
    const urdf::Link* link = stack.back();
    stack.pop_back();
    std::vector<urdf::GeometrySharedPtr> shapes;
    for (const auto& v : link->visual_array) if (v) shapes.push_back(v->geometry);
    for (const auto& c : link->collision_array) if (c) shapes.push_back(c->geometry);
    for (const auto& g : shapes) {
      if (!g || g->type != urdf::Geometry::MESH) continue;
      ++meshes;
      const std::string& name = static_cast<const urdf::Mesh&>(*g).filename;
      if (!MeshResolves(name, dir)) unresolved.push_back(link->name + ": " + name);
    }
    for (const auto& child : link->child_links) stack.push_back(child.get());
  }
  if (unresolved.empty()) return;
  std::sort(unresolved.begin(), unresolved.end());
  unresolved.erase(std::unique(unresolved.begin(), unresolved.end()), unresolved.end());
  std::string list;
  for (size_t k = 0; k < unresolved.size() && k < 3; ++k) list += (k ? "; " : "") + unresolved[k];
  if (unresolved.size() > 3) list += "; ...";
  warnings->push_back(source + ": " + std::to_string(unresolved.size()) + " of " +
                      std::to_string(meshes) + " mesh files cannot be resolved (" + list +
                      "); package:// paths are looked up in ROS_PACKAGE_PATH and "
                      "AMENT_PREFIX_PATH. The twin does not load meshes: it draws capsules "
                      "along the links, for rendering and collisions");
}

// Warns about moving bodies without mass (no <inertial> on any link they carry).
void WarnMassless(const KinematicModel& model, const std::vector<JointPtr>& moving,
                  const std::string& source, std::vector<std::string>* warnings) {
  std::vector<std::string> joints;
  for (int k = 0; k < model.num_joints(); ++k) {
    if (!(model.links[k].inertia.mass > 0.0)) joints.push_back(moving[k]->name);
  }
  if (joints.empty()) return;
  std::ostringstream os;
  os << source << ": no <inertial> on the links moved by joint"
     << (joints.size() > 1 ? "s " : " ") << ListNames(joints)
     << " (up to the next moving joint): the twin simulates each such link with a stand-in of "
     << kFallbackLinkMassKg << " kg and " << kFallbackLinkInertiaKgm2
     << " kg m^2 at its joint, and gravity-driven terms (joint compliance, the diagnosis's "
        "gravity torques) see no mass there; add <inertial> elements for realistic gravity "
        "effects";
  warnings->push_back(os.str());
}

// ---- URDF writing ---------------------------------------------------------------------------

// URDF rpy of R = Rz(yaw) Ry(pitch) Rx(roll); roll comes from the residual rotation so the
// result stays exact near pitch = +-90 deg.
Vector3 RollPitchYaw(const Matrix3& R) {
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  const double pitch = std::atan2(-R(2, 0), std::hypot(R(0, 0), R(1, 0)));
  const Matrix3 R_yp = RotZ(yaw) * Eigen::AngleAxisd(pitch, Vector3::UnitY()).matrix();
  const Matrix3 M = R_yp.transpose() * R;  // RotX(roll)
  return Vector3(std::atan2(M(2, 1), M(1, 1)), pitch, yaw);
}

std::string XmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

void WriteOrigin(std::ostream& os, const Transform& X) {
  // Adding 0.0 turns -0 into 0 in the text.
  const Vector3 p = X.translation() + Vector3::Zero();
  const Vector3 rpy = RollPitchYaw(X.linear()) + Vector3::Zero();
  const auto N = ShortestNumber;
  os << "<origin xyz=\"" << N(p.x()) << ' ' << N(p.y()) << ' ' << N(p.z()) << "\" rpy=\""
     << N(rpy.x()) << ' ' << N(rpy.y()) << ' ' << N(rpy.z()) << "\"/>";
}

// A link whose inertia is given in frame L, posed X_UL in the URDF link frame U.
void WriteLink(std::ostream& os, const std::string& name, const LinkInertia& in,
               const Transform& X_UL) {
  if (!(in.mass > 0.0)) {
    os << "  <link name=\"" << name << "\"/>\n";
    return;
  }
  Transform X_UI = X_UL;
  X_UI.translation() = X_UL * in.p_LiCom;
  const Matrix3& I = in.I_Com;
  os << "  <link name=\"" << name << "\">\n    <inertial>\n      ";
  WriteOrigin(os, X_UI);
  const auto N = ShortestNumber;
  os << "\n      <mass value=\"" << N(in.mass) << "\"/>\n      <inertia ixx=\"" << N(I(0, 0))
     << "\" ixy=\"" << N(I(0, 1)) << "\" ixz=\"" << N(I(0, 2)) << "\" iyy=\"" << N(I(1, 1))
     << "\" iyz=\"" << N(I(1, 2)) << "\" izz=\"" << N(I(2, 2)) << "\"/>\n    </inertial>\n  </link>\n";
}

void WriteJoint(std::ostream& os, const std::string& name, const std::string& parent,
                const std::string& child, const Transform& X, const JointLimits* limits) {
  os << "  <joint name=\"" << name << "\" type=\"" << (limits ? "revolute" : "fixed") << "\">\n"
     << "    <parent link=\"" << parent << "\"/>\n    <child link=\"" << child << "\"/>\n    ";
  WriteOrigin(os, X);
  os << "\n";
  if (limits) {
    os << "    <axis xyz=\"0 0 1\"/>\n    <limit lower=\"" << ShortestNumber(limits->lower)
       << "\" upper=\"" << ShortestNumber(limits->upper) << "\" effort=\"100\" velocity=\"3\"/>\n";
  }
  os << "  </joint>\n";
}

// M_i = TransZ(d) TransX(a) RotX(alpha) RotY(beta): link i's transform after its RotZ.
Transform AfterRotZ(const DhParameters& dh) {
  DhParameters m = dh;
  m.theta_offset = 0.0;
  return LinkTransform(m, 0.0);
}

Transform RotZTransform(double angle) {
  Transform X = Transform::Identity();
  X.linear() = RotZ(angle);
  return X;
}

}  // namespace

KinematicModel ParseUrdf(const std::string& text, const std::string& source,
                         const UrdfImportOptions& options, std::vector<std::string>* warnings) {
  std::vector<std::string> ignored;
  if (!warnings) warnings = &ignored;
  const urdf::ModelInterfaceSharedPtr urdf = ParseText(text, source);
  CheckPlausible(*urdf, text, source);
  const std::string base_name =
      options.base_link.empty() ? urdf->getRoot()->name : options.base_link;
  const urdf::LinkConstSharedPtr base = RequireLink(*urdf, base_name, "base_link", source);
  const std::string tip =
      options.tip_link.empty() ? DefaultTip(*urdf, *base, source, warnings) : options.tip_link;
  RequireLink(*urdf, tip, "tip_link", source);

  const std::vector<JointPtr> chain = JointsBetween(*urdf, base_name, tip, source);
  const std::vector<JointPtr> moving = MovingJoints(chain, base_name, tip, source);
  std::vector<AxisLine> axes;
  const Transform X_BT = ChainAtZero(chain, source, &axes);

  KinematicModel model(static_cast<int>(moving.size()));
  model.name = options.robot_name.empty() ? urdf->getName() : options.robot_name;
  BuildGeometry(axes, X_BT, moving, source, &model);
  for (int i = 0; i < model.num_joints(); ++i) {
    model.links[i].limits = LimitsOf(*moving[i], source);
    model.links[i].joint_name = moving[i]->name;
  }
  AssignInertias(*urdf, *base, moving, &model);
  ValidateModel(model, source);
  WarnMeshes(*base, source, warnings);
  WarnMassless(model, moving, source, warnings);
  return model;
}

KinematicModel LoadUrdf(const std::string& path, const UrdfImportOptions& options,
                        std::vector<std::string>* warnings) {
  return ParseUrdf(ReadTextFile(path, kMaxUrdfBytes), path, options, warnings);
}

std::string ModelToUrdf(const KinematicModel& model) {
  std::ostringstream os;
  // The comment marks the file as twinbench's: `export-urdf --out` replaces only such files.
  os << "<?xml version=\"1.0\"?>\n" << kWrittenByComment << "\n<robot name=\""
     << XmlEscape(model.name) << "\">\n";
  os << "  <link name=\"base_link\"/>\n";
  // URDF link i is U_i = L(i-1) RotZ(theta_i + q_i); L_i = U_i M_i.
  std::string parent = "base_link";
  Transform X_parent_joint = model.X_BL0;
  for (int i = 0; i < model.num_joints(); ++i) {
    const Link& l = model.links[i];
    const std::string child = "link" + std::to_string(i + 1);
    WriteLink(os, child, l.inertia, AfterRotZ(l.dh));
    WriteJoint(os, "joint" + std::to_string(i + 1), parent, child,
               X_parent_joint * RotZTransform(l.dh.theta_offset), &l.limits);
    parent = child;
    X_parent_joint = AfterRotZ(l.dh);
  }
  WriteLink(os, "tool", model.tool().inertia, Transform::Identity());
  WriteJoint(os, "tool_joint", parent, "tool",
             X_parent_joint * LinkTransform(model.tool().dh, 0.0), nullptr);
  os << "  <link name=\"end\"/>\n";
  WriteJoint(os, "end_joint", "tool", "end", model.X_LtE, nullptr);
  os << "</robot>\n";
  return os.str();
}

}  // namespace twin
