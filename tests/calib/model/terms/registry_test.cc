// The error-term registry and every registered term: names, checks, the Jacobian of the model's
// forward kinematics with respect to the term's parameters (autodiff, as the engine uses it)
// against central finite differences, and each term's stage formula on hand-computed cases.
#include <cmath>
#include <limits>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "calib/model/error_term.h"
#include "calib/model/parameter_layout.h"
#include "calib/model/robot_model.h"
#include "test_models.h"

namespace twin {
namespace {

using testing::RandomJoints;
using testing::ReinovoLikeModel;

// A context with readings, random approach directions, a time stamp and a temperature.
MeasurementContext FullContext(const KinematicModel& m, std::mt19937_64& rng) {
  MeasurementContext c;
  c.q = RandomJoints(m, rng);
  c.approach = JointVector::Zero(m.num_joints());
  std::bernoulli_distribution coin(0.5);
  for (int i = 0; i < m.num_joints(); ++i) c.approach(i) = coin(rng) ? 1.0 : -1.0;
  c.time_s = std::uniform_real_distribution<double>(0.0, 3600.0)(rng);
  c.temperature_delta_K = std::uniform_real_distribution<double>(-5.0, 15.0)(rng);
  return c;
}

// One example spec of every registered type, acting where it is visible on a floor arm.
std::vector<TermSpec> ExampleSpecs() {
  return {{"joint_compliance", 1, {}},   {"transmission_error", 3, {1, 2}},
          {"backlash", 2, {}},           {"thermal_growth", -1, {}},
          {"thermal_drift", -1, {}},     {"mount_deflection", -1, {}},
          {"thermal_warmup", -1, {30}},  {"lateral_compliance", 0, {}},
          {"axis_wobble", 2, {2}}};
}

RobotModel ModelWithAllTerms(const KinematicModel& chain, std::mt19937_64& rng) {
  RobotModel m = MakeRobotModel(chain);
  for (const TermSpec& s : ExampleSpecs()) m = WithTerm(m, MakeErrorTerm(s, chain, chain.name));
  // Realistic magnitudes: compliance 1e-5 rad/(N m), gear errors 0.01 deg, backlash 0.005 deg,
  // 1.2e-5 /K, 1e-9 /s, mount deflection 0.05 mm, a warm-up growth of 1e-4 and a time
  // constant 1.2 times its order, lateral compliance 2e-6 rad/(N m) with gravity tilted by
  // 0.01 rad, a wobble of 5e-5 rad.
  std::uniform_real_distribution<double> u(0.5, 1.5);
  const double values[] = {1e-5,  2e-4, -1e-4, 1e-4, 5e-5, -9e-5, 1.2e-5,
                           1e-9,  5e-5, -3e-5, 4e-5, 1e-4, 0.18,
                           2e-6,  -1e-6, 2e-8,  -1e-8, 5e-5, -4e-5, 3e-5, 6e-5};
  constexpr int kValues = sizeof(values) / sizeof(values[0]);
  EXPECT_EQ(m.term_values.size(), kValues) << "one example value per term parameter";
  for (int i = 0; i < m.term_values.size() && i < kValues; ++i) {
    m.term_values(i) = values[i] * u(rng);
  }
  return m;
}

TEST(ErrorTermRegistry, EveryTypeIsRegisteredOnceAndItsExampleBuilds) {
  const std::vector<std::string> types = ErrorTermTypes();
  EXPECT_EQ(std::set<std::string>(types.begin(), types.end()).size(), types.size());
  std::set<std::string> covered;
  const KinematicModel chain = ReinovoLikeModel();
  for (const TermSpec& s : ExampleSpecs()) {
    const auto term = MakeErrorTerm(s, chain, "r1");
    EXPECT_EQ(term->spec().type, s.type);
    EXPECT_FALSE(term->parameters().empty()) << s.type;
    covered.insert(s.type);
  }
  EXPECT_EQ(covered, std::set<std::string>(types.begin(), types.end()))
      << "a registered term has no example here";
}

TEST(ErrorTermRegistry, ParametersAreNamedAfterRobotJointAndOrder) {
  const KinematicModel chain = ReinovoLikeModel();
  EXPECT_EQ(MakeErrorTerm({"joint_compliance", 1, {}}, chain, "r1")->parameters()[0].name,
            "r1.joint2.compliance");
  const auto te = MakeErrorTerm({"transmission_error", 3, {2}}, chain, "r1");
  ASSERT_EQ(te->parameters().size(), 2u);
  EXPECT_EQ(te->parameters()[0].name, "r1.joint4.harmonic2.sin");
  EXPECT_EQ(te->parameters()[1].name, "r1.joint4.harmonic2.cos");
  EXPECT_EQ(MakeErrorTerm({"backlash", 2, {}}, chain, "r1")->parameters()[0].name,
            "r1.joint3.backlash");
  EXPECT_EQ(MakeErrorTerm({"thermal_growth", -1, {}}, chain, "r1")->parameters()[0].unit, "1/K");
  EXPECT_EQ(TermLabel({"transmission_error", 3, {1, 2}}), "transmission_error (joint 4, order 1, 2)");
  EXPECT_EQ(TermLabel({"thermal_drift", -1, {}}), "thermal_drift");
  EXPECT_EQ(TermLabel({"thermal_warmup", -1, {20}}), "thermal_warmup (time constant 20 min)");
  EXPECT_EQ(MakeErrorTerm({"thermal_warmup", -1, {20}}, chain, "r1")->parameters()[0].name,
            "r1.thermal.warmup_growth");
}

TEST(ErrorTermRegistry, BadSpecsAreInputErrorsNamingWhatIsWrong) {
  const KinematicModel chain = ReinovoLikeModel();
  auto message = [&](const TermSpec& s) {
    try {
      MakeErrorTerm(s, chain, "r1", "diagnosis.terms[0]");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message({"joint_stiction", 1, {}}).find("unknown error term \"joint_stiction\""),
            std::string::npos);
  EXPECT_NE(message({"joint_stiction", 1, {}}).find("joint_compliance"), std::string::npos);
  EXPECT_NE(message({"backlash", 6, {}}).find("joint from 1 to 6, got 7"), std::string::npos);
  EXPECT_NE(message({"thermal_growth", 2, {}}).find("takes no joint"), std::string::npos);
  EXPECT_NE(message({"transmission_error", 1, {}}).find("needs harmonic orders"),
            std::string::npos);
  EXPECT_NE(message({"transmission_error", 1, {2, 2}}).find("distinct"), std::string::npos);
  EXPECT_NE(message({"backlash", 1, {2}}).find("takes no harmonic orders"), std::string::npos);
  EXPECT_NE(message({"backlash", 1, {2}}).find("diagnosis.terms[0]"), std::string::npos);
  EXPECT_NE(message({"thermal_warmup", -1, {}}).find("time constant in whole minutes"),
            std::string::npos);
  EXPECT_NE(message({"thermal_warmup", -1, {0}}).find("from 1 to 1440"), std::string::npos);
  EXPECT_NE(message({"thermal_warmup", 2, {30}}).find("takes no joint"), std::string::npos);
}

TEST(ErrorTermRegistry, CandidatesCoverEveryJointAndOrdersOneAndTwo) {
  const KinematicModel chain = ReinovoLikeModel();
  const std::vector<TermSpec> c = CandidateTermSpecs(chain);
  int compliance = 0, harmonics = 0, backlash = 0, robot = 0;
  for (const TermSpec& s : c) {
    if (s.type == "joint_compliance") ++compliance;
    if (s.type == "transmission_error") ++harmonics;
    if (s.type == "backlash") ++backlash;
    if (s.joint == -1) ++robot;
    EXPECT_NO_THROW(MakeErrorTerm(s, chain, "r1")) << TermLabel(s);
  }
  EXPECT_EQ(compliance, 6);
  EXPECT_EQ(harmonics, 12);  // 6 joints x orders {1}, {2}
  EXPECT_EQ(backlash, 6);
  EXPECT_EQ(robot, 7);  // thermal growth, thermal drift, mount deflection, 4 warm-up times
  int warmups = 0;
  for (const TermSpec& s : c) warmups += s.type == "thermal_warmup" && s.orders.size() == 1;
  EXPECT_EQ(warmups, 4);
}

TEST(ErrorTermJacobian, AutodiffOfEveryTermMatchesCentralFiniteDifferences) {
  std::mt19937_64 rng(21);
  const KinematicModel chain = testing::Perturbed(ReinovoLikeModel(), rng, 0.002, 0.003);
  const RobotModel model = ModelWithAllTerms(chain, rng);
  const ParameterLayout layout(model);
  const Eigen::VectorXd p0 = GetParameters(model);
  const int n = layout.size();
  for (int trial = 0; trial < 10; ++trial) {
    const MeasurementContext c = FullContext(chain, rng);
    for (int k = layout.geometry_size(); k < n; ++k) {
      // Derivative of p_BE with respect to parameter k by a one-dimensional jet.
      std::vector<Jet> x(n);
      for (int i = 0; i < n; ++i) x[i] = Jet(p0(i));
      x[k].v[0] = 1.0;
      const RigidT<Jet> X = RobotEndPoseT<Jet>(model, x.data(), c);
      Vector3 autodiff;
      for (int r = 0; r < 3; ++r) autodiff(r) = X.p(r).v[0];
      // Central difference with a step of 1e-6 of the parameter's scale.
      const double h = 1e-6 * layout[k].scale;
      Eigen::VectorXd pp = p0, pm = p0;
      pp(k) += h;
      pm(k) -= h;
      const Vector3 fd = (RobotEndPoseT<double>(model, pp.data(), c).p -
                          RobotEndPoseT<double>(model, pm.data(), c).p) /
                         (2 * h);
      // Relative to the scale: the derivative per scaled unit is O(1 m); central differences
      // err by (h/scale)^2 = 1e-12 of the curvature plus 1e-16 / 1e-6 = 1e-10 of rounding, so
      // 1e-7 m per scaled unit is a wide margin and far below a wrong derivative (O(0.1 m)).
      EXPECT_LT((autodiff - fd).norm() * layout[k].scale, 1e-7) << layout[k].name;
      EXPECT_GT(autodiff.norm() * layout[k].scale, 1e-6) << layout[k].name << " has no effect";
    }
  }
}

TEST(ErrorTermStages, EachFormulaHoldsOnAHandComputedCase) {
  const KinematicModel chain = ReinovoLikeModel();
  MeasurementContext c;
  c.q = (JointVector(6) << 0.1, -0.4, 0.3, 0.7, 1.1, -0.5).finished();
  c.approach = (JointVector(6) << 1, -1, 1, 1, -1, 0).finished();
  c.time_s = 1200.0;
  c.temperature_delta_K = 8.0;
  auto joints_after = [&](const TermSpec& s, const std::vector<double>& p) {
    const auto t = MakeErrorTerm(s, chain, "r1");
    JointVector q = c.q;
    t->OffsetJoints(p.data(), c, q.data());
    return q;
  };
  // Transmission error, orders 1 and 2 on joint 4: s1 sin q + c1 cos q + s2 sin 2q + c2 cos 2q.
  const JointVector te = joints_after({"transmission_error", 3, {1, 2}}, {1e-4, 2e-4, 3e-4, 4e-4});
  const double q4 = c.q(3);
  // 1e-15: a few roundings of terms of 1e-4 added to an angle of 0.7 rad.
  EXPECT_NEAR(te(3) - q4,
              1e-4 * std::sin(q4) + 2e-4 * std::cos(q4) + 3e-4 * std::sin(2 * q4) +
                  4e-4 * std::cos(2 * q4),
              1e-15);
  EXPECT_EQ(te(2), c.q(2));
  // Backlash on joint 2 approached from above (-1): b * (-1).
  // 1e-16: one rounding of the sum with the angle -0.4 rad (its ulp is 5.6e-17).
  EXPECT_NEAR(joints_after({"backlash", 1, {}}, {-5e-5})(1) - c.q(1), 5e-5, 1e-16);
  // Thermal growth: scale 1 + k dT; drift: 1 + r t.
  double s = 1.0;
  MakeErrorTerm({"thermal_growth", -1, {}}, chain, "r1")->ScaleLengths(std::vector{1.2e-5}.data(),
                                                                       c, &s);
  EXPECT_DOUBLE_EQ(s, 1.0 + 1.2e-5 * 8.0);
  s = 1.0;
  MakeErrorTerm({"thermal_drift", -1, {}}, chain, "r1")->ScaleLengths(std::vector{2e-9}.data(), c,
                                                                      &s);
  EXPECT_DOUBLE_EQ(s, 1.0 + 2e-9 * 1200.0);
  // Compliance: q_i += c tau_i.
  const double tau[6] = {0, 55.0, -12.0, 0, 0, 0};
  JointVector q = c.q;
  MakeErrorTerm({"joint_compliance", 1, {}}, chain, "r1")->Sag(std::vector{2e-5}.data(), tau,
                                                               q.data());
  // 1e-16: one rounding of the sum with the angle -0.4 rad (its ulp is 5.6e-17).
  EXPECT_NEAR(q(1) - c.q(1), 2e-5 * 55.0, 1e-16);
  // Mount deflection: gravity along -z of B; with the flange turned so x_F points down, the
  // point moves by d_x along x_F.
  Mat3T<double> R_BF;
  R_BF << 0, 0, 1, 0, 1, 0, -1, 0, 0;  // x_F = -z_B
  Vec3T<double> dp = Vec3T<double>::Zero();
  MakeErrorTerm({"mount_deflection", -1, {}}, chain, "r1")
      ->OffsetTool(std::vector{4e-5, 1e-5, 2e-5}.data(), R_BF, -Vector3::UnitZ(), &dp);
  EXPECT_NEAR(dp(0), 4e-5, 1e-20);
  EXPECT_NEAR(dp(1), 0.0, 1e-20);
  EXPECT_NEAR(dp(2), 0.0, 1e-20);
}

// What model discovery's size test tells from zero (ErrorTerm::SizeMeasures) and what drives
// each term (ErrorTerm::driver).
TEST(ErrorTermSize, AmplitudesByDefaultAndAWarmUpsGrowthByTheSessionsEnd) {
  const KinematicModel chain = ReinovoLikeModel();
  // The default: the amplitudes themselves, with an identity Jacobian.
  const auto te = MakeErrorTerm({"transmission_error", 3, {1, 2}}, chain, "r1");
  const std::vector<double> a{1e-4, -2e-4, 3e-4, 4e-4};
  Eigen::MatrixXd J;
  Eigen::VectorXd size = te->SizeMeasures(a.data(), 900.0, &J);
  ASSERT_EQ(size.size(), 4);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(size(k), a[k]);
  EXPECT_TRUE(J.isApprox(Eigen::MatrixXd::Identity(4, 4))) << J;
  // The warm-up of order 30 (tau0 = 1800 s), g = 2e-4, l = 0.3, over a 900 s session:
  // g (1 - exp(-900 / (1800 e^0.3))).
  const auto w = MakeErrorTerm({"thermal_warmup", -1, {30}}, chain, "r1");
  const std::vector<double> p{2e-4, 0.3};
  size = w->SizeMeasures(p.data(), 900.0, &J);
  ASSERT_EQ(size.size(), 1);
  ASSERT_EQ(J.rows(), 1);
  ASSERT_EQ(J.cols(), 2);
  const auto growth = [&](double g, double l) {
    return g * (1.0 - std::exp(-900.0 / (1800.0 * std::exp(l))));
  };
  // 1e-18: the closed form against the same in other words, rounding of a 1e-4 figure.
  EXPECT_NEAR(size(0), growth(p[0], p[1]), 1e-18);
  // Its Jacobian against central differences (steps 1e-9 and 1e-5: the truncation error is
  // their square times the second derivative, below 1e-10 relative; the tolerance 1e-7).
  const double dg = (growth(p[0] + 1e-9, p[1]) - growth(p[0] - 1e-9, p[1])) / 2e-9;
  const double dl = (growth(p[0], p[1] + 1e-5) - growth(p[0], p[1] - 1e-5)) / 2e-5;
  EXPECT_NEAR(J(0, 0), dg, 1e-7 * std::abs(dg));
  EXPECT_NEAR(J(0, 1), dl, 1e-7 * std::abs(dl));
  // Without a time stamp: the final growth alone, as the default.
  size = w->SizeMeasures(p.data(), std::numeric_limits<double>::quiet_NaN(), &J);
  ASSERT_EQ(size.size(), 1);
  EXPECT_EQ(size(0), p[0]);
  EXPECT_TRUE(J.isApprox((Eigen::MatrixXd(1, 2) << 1.0, 0.0).finished())) << J;
  // Drivers: the clock for the drift (without bound) and the warm-up (levelling off), a
  // measured quantity for every other term.
  for (const TermSpec& spec : ExampleSpecs()) {
    const TermDriver d = MakeErrorTerm(spec, chain, "r1")->driver();
    const TermDriver expected = spec.type == "thermal_drift"    ? TermDriver::kClockUnbounded
                                : spec.type == "thermal_warmup" ? TermDriver::kClockLevelling
                                                                : TermDriver::kMeasured;
    EXPECT_EQ(d, expected) << spec.type;
  }
}

TEST(ErrorTermContext, TermsNameWhatTheContextLacks) {
  const KinematicModel chain = ReinovoLikeModel();
  RobotModel m = MakeRobotModel(chain);
  const MeasurementContext bare = ContextOf(MidRange(chain));
  EXPECT_EQ(MissingContext(m, bare), "");
  m = WithTerm(m, MakeErrorTerm({"thermal_growth", -1, {}}, chain, "r1"));
  EXPECT_EQ(MissingContext(m, bare), "thermal_growth: needs a temperature change");
  RobotModel b = WithTerm(MakeRobotModel(chain), MakeErrorTerm({"backlash", 0, {}}, chain, "r1"));
  EXPECT_NE(MissingContext(b, bare).find("approach direction"), std::string::npos);
  RobotModel d =
      WithTerm(MakeRobotModel(chain), MakeErrorTerm({"thermal_drift", -1, {}}, chain, "r1"));
  EXPECT_NE(MissingContext(d, bare).find("time stamp"), std::string::npos);
  EXPECT_THROW(WithTerm(b, MakeErrorTerm({"backlash", 0, {}}, chain, "r1")), InputError);
}

}  // namespace
}  // namespace twin
