// Error terms of the estimator's robot model (DESIGN.md, "the estimator model"): physical
// effects beyond the geometric chain, each with named parameters that the identification
// engine can estimate. One file per term under calib/model/terms/ with its formula in the
// comment above it, plus one line in the registry (calib/model/terms/registry.cc).
//
// A term acts at one or more stages of the forward kinematics (calib/model/robot_model.h):
//   1. joint angles: link angle = reading + offset (transmission error, backlash);
//   2. lengths: every d and a of the chain times a scale (thermal growth and drift);
//   3. gravity sag: link angle += c * (gravity torque about the joint), solved together with
//      the configuration it changes (joint compliance);
//   4. tool point: the end point moves in the flange frame (mount deflection);
//   5. axis deflections: small rotations of the chain at each joint, before the joint turns,
//      given the frames of the chain after stages 1-3 (lumped-mass joint compliance, lateral
//      compliance of a joint's bearing or of the base, a wobbling axis).
// Terms are written independently of sim/effects (the truth side): a formula shared between
// what simulates and what estimates would hide its own mistake.
//
// Each stage exists for double and for ceres::Jet<double, kJetStride> (the scalar of the
// engine's dynamic autodiff); a term writes each stage once, as a template, and ErrorTermT
// instantiates it for both scalars.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <ceres/jet.h>

#include "calib/kinematics/kinematic_model.h"
#include "calib/kinematics/rigid_transform.h"
#include "calib/model/measurement_context.h"

namespace twin {

/// Derivative stride of the engine's ceres::DynamicAutoDiffCostFunction; terms and the robot
/// model's forward kinematics are instantiated for this jet.
constexpr int kJetStride = 8;
using Jet = ceres::Jet<double, kJetStride>;

/// One named parameter of a term.
struct TermParameter {
  std::string name;   ///< full name, e.g. "r1.joint2.compliance"
  std::string unit;   ///< SI unit of the value, e.g. "rad/(N m)"
  /// Size of one scaled unit in SI for the observability analysis: the change of this
  /// parameter that moves a ~1 m arm's tool by about as much as 1 rad of joint angle.
  double scale = 1.0;
};

/// What a term is made from: its registry type, the joint it acts on (0-based; -1 for terms of
/// the whole robot) and, for periodic terms, the harmonic orders.
struct TermSpec {
  std::string type;         ///< registry name, e.g. "joint_compliance"
  int joint = -1;           ///< 0-based joint, or -1
  std::vector<int> orders;  ///< harmonic orders (transmission error), >= 1 each
};

/// What drives an error term, in the order model discovery prefers them where the held-out
/// data cannot tell two candidates apart (calib/diagnosis/model_discovery.h, step 3): a
/// quantity read with each measurement (joint angles, a temperature, the flange's attitude);
/// the session's clock through an effect that levels off (a warm-up); the clock through one
/// that grows without end (a drift linear in time). A clock-driven model is used at later
/// times than it was fitted on, and the held-out regions of one session cannot test that.
enum class TermDriver { kMeasured = 0, kClockLevelling = 1, kClockUnbounded = 2 };

/// What stage 5 gives a term: the frames of the chain after stages 1-3 and gravity.
template <typename T>
struct DeflectionInputT {
  const RigidT<T>* X_BL = nullptr;  ///< frames L0..Lt in B (N + 2 entries)
  Vec3T<T> p_BE = Vec3T<T>::Zero();  ///< the end point in B (before stage 4)
  Vector3 g_B = -Vector3::UnitZ();  ///< gravity direction in B (unit)
  double gravity = 9.80665;          ///< its magnitude [m/s^2]
};

/// One error term (interface). Parameters are passed as a pointer to the term's own slice of
/// the model's flat parameter vector (ParameterLayout); stages add to what they are given.
class ErrorTerm {
 public:
  virtual ~ErrorTerm() = default;
  /// The spec it was made from.
  virtual const TermSpec& spec() const = 0;
  /// Its parameters, in the order of its slice.
  virtual const std::vector<TermParameter>& parameters() const = 0;
  /// Empty when `context` has what the term needs, else what is missing (e.g. "a temperature").
  virtual std::string Requires(const MeasurementContext& context) const = 0;
  /// True for terms with a gravity-sag stage (stage 3).
  virtual bool sags_under_gravity() const { return false; }
  /// True for terms with a tool-offset stage (stage 4).
  virtual bool offsets_tool() const { return false; }
  /// True for terms with an axis-deflection stage (stage 5).
  virtual bool deflects_axes() const { return false; }
  /// How many of its parameters, leading its slice, are amplitudes: at zero the term does
  /// nothing. The rest shape the effect (a time constant) and have no "no effect" value.
  /// Default: every parameter.
  virtual int amplitude_parameters() const { return static_cast<int>(parameters().size()); }
  /// What drives the term (TermDriver); a quantity read with each measurement by default.
  virtual TermDriver driver() const { return TermDriver::kMeasured; }
  /// What model discovery's size test tells from zero: measures of the term's effect as
  /// functions of its parameters p, with their Jacobian (measures x parameters). By default its
  /// amplitude parameters themselves. A term whose amplitude alone is poorly determined where its
  /// effect is not says what the effect amounts to instead: a warm-up slow against the session
  /// trades its final growth against its time constant, while the growth it reaches by the
  /// data's latest time stamp `session_s` [s] (NaN: none) is well determined.
  virtual Eigen::VectorXd SizeMeasures(const double* p, double session_s,
                                       Eigen::MatrixXd* jacobian) const {
    (void)session_s;
    const int a = amplitude_parameters();
    *jacobian = Eigen::MatrixXd::Zero(a, static_cast<Eigen::Index>(parameters().size()));
    jacobian->leftCols(a).setIdentity();
    return Eigen::Map<const Eigen::VectorXd>(p, a);
  }
  /// True when some parameters act only once others are non-zero (a time constant while the
  /// amplitude is zero): at zero they have no gradient, so model discovery fits such a term a
  /// second time from its first solution.
  bool has_dormant_parameters() const {
    return amplitude_parameters() < static_cast<int>(parameters().size());
  }

  /// Stage 1: adds to the link angles q (N entries) [rad].
  virtual void OffsetJoints(const double* p, const MeasurementContext& c, double* q) const = 0;
  virtual void OffsetJoints(const Jet* p, const MeasurementContext& c, Jet* q) const = 0;
  /// Stage 2: multiplies the length scale s [-].
  virtual void ScaleLengths(const double* p, const MeasurementContext& c, double* s) const = 0;
  virtual void ScaleLengths(const Jet* p, const MeasurementContext& c, Jet* s) const = 0;
  /// Stage 3: adds to the link angles q given the gravity torques tau (N entries) [N m].
  virtual void Sag(const double* p, const double* tau, double* q) const = 0;
  virtual void Sag(const Jet* p, const Jet* tau, Jet* q) const = 0;
  /// Stage 4: adds to the end point's offset dp_F in the flange frame [m], given the flange's
  /// rotation R_BF and the gravity direction g_B (unit, base frame).
  virtual void OffsetTool(const double* p, const Mat3T<double>& R_BF, const Vector3& g_B,
                          Vec3T<double>* dp_F) const = 0;
  virtual void OffsetTool(const Jet* p, const Mat3T<Jet>& R_BF, const Vector3& g_B,
                          Vec3T<Jet>* dp_F) const = 0;
  /// Stage 5: adds to w (3 entries per joint i, 0-based) the small rotation vector [rad] that
  /// turns the chain at frame X_BL[i] (the frame joint i turns about its z, before it turns),
  /// in that frame's axes: x and y tilt joint i's axis and everything beyond it, z adds to its
  /// angle. Given the chain's frames after stages 1-3 (`in`) and the context.
  virtual void DeflectAxes(const double* p, const MeasurementContext& c,
                           const DeflectionInputT<double>& in, double* w) const = 0;
  virtual void DeflectAxes(const Jet* p, const MeasurementContext& c,
                           const DeflectionInputT<Jet>& in, Jet* w) const = 0;
};

/// CRTP helper: a term writes the stages it has as member templates named OffsetJointsT,
/// ScaleLengthsT, SagT, OffsetToolT and DeflectAxesT; the others keep these do-nothing defaults.
template <class Derived>
class ErrorTermT : public ErrorTerm {
 public:
  ErrorTermT(TermSpec spec, std::vector<TermParameter> parameters)
      : spec_(std::move(spec)), parameters_(std::move(parameters)) {}
  const TermSpec& spec() const final { return spec_; }
  const std::vector<TermParameter>& parameters() const final { return parameters_; }
  std::string Requires(const MeasurementContext&) const override { return ""; }

  void OffsetJoints(const double* p, const MeasurementContext& c, double* q) const final {
    self().OffsetJointsT(p, c, q);
  }
  void OffsetJoints(const Jet* p, const MeasurementContext& c, Jet* q) const final {
    self().OffsetJointsT(p, c, q);
  }
  void ScaleLengths(const double* p, const MeasurementContext& c, double* s) const final {
    self().ScaleLengthsT(p, c, s);
  }
  void ScaleLengths(const Jet* p, const MeasurementContext& c, Jet* s) const final {
    self().ScaleLengthsT(p, c, s);
  }
  void Sag(const double* p, const double* tau, double* q) const final { self().SagT(p, tau, q); }
  void Sag(const Jet* p, const Jet* tau, Jet* q) const final { self().SagT(p, tau, q); }
  void OffsetTool(const double* p, const Mat3T<double>& R_BF, const Vector3& g_B,
                  Vec3T<double>* dp_F) const final {
    self().OffsetToolT(p, R_BF, g_B, dp_F);
  }
  void OffsetTool(const Jet* p, const Mat3T<Jet>& R_BF, const Vector3& g_B,
                  Vec3T<Jet>* dp_F) const final {
    self().OffsetToolT(p, R_BF, g_B, dp_F);
  }
  void DeflectAxes(const double* p, const MeasurementContext& c,
                   const DeflectionInputT<double>& in, double* w) const final {
    self().DeflectAxesT(p, c, in, w);
  }
  void DeflectAxes(const Jet* p, const MeasurementContext& c, const DeflectionInputT<Jet>& in,
                   Jet* w) const final {
    self().DeflectAxesT(p, c, in, w);
  }

  template <typename T>
  void OffsetJointsT(const T*, const MeasurementContext&, T*) const {}
  template <typename T>
  void ScaleLengthsT(const T*, const MeasurementContext&, T*) const {}
  template <typename T>
  void SagT(const T*, const T*, T*) const {}
  template <typename T>
  void OffsetToolT(const T*, const Mat3T<T>&, const Vector3&, Vec3T<T>*) const {}
  template <typename T>
  void DeflectAxesT(const T*, const MeasurementContext&, const DeflectionInputT<T>&, T*) const {}

 private:
  const Derived& self() const { return static_cast<const Derived&>(*this); }
  TermSpec spec_;
  std::vector<TermParameter> parameters_;
};

/// Builds the term named by spec.type for robot `robot_name` (prefix of its parameter names)
/// with the nominal chain `nominal` (masses, lengths); throws InputError naming `where` for an
/// unknown type (listing the known ones), a joint outside the chain, or bad orders.
std::shared_ptr<const ErrorTerm> MakeErrorTerm(const TermSpec& spec, const KinematicModel& nominal,
                                               const std::string& robot_name,
                                               const std::string& where = "error term");

/// Registry names of every error term type.
std::vector<std::string> ErrorTermTypes();

/// Highest harmonic order a periodic term may have (registry.cc).
int MaxHarmonicOrder();

/// Every instance of every registered term that model discovery tries for `nominal`: each
/// joint for per-joint terms, one candidate per harmonic order for periodic ones (joint j's
/// orders `orders[j]`; orders 1 and 2 for every joint when `orders` is empty), one for
/// whole-robot terms.
std::vector<TermSpec> CandidateTermSpecs(const KinematicModel& nominal,
                                         const std::vector<std::vector<int>>& orders = {});

/// Readable label of a spec, e.g. "joint_compliance (joint 2)" or "transmission_error (joint 4,
/// order 2)" (joints 1-based).
std::string TermLabel(const TermSpec& spec);

}  // namespace twin
