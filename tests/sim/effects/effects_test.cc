#include "sim/effects/effect.h"

#include <cmath>
#include <initializer_list>
#include <map>
#include <random>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "calib/model/parameters.h"
#include "tests/calib/test_models.h"

namespace twin {
namespace {

constexpr char kWhere[] = "scenarios/test.yaml effects[0]";

EffectSpec Spec(const std::string& type, const std::map<std::string, double>& params,
                int robot = -1, int joint = -1) {
  EffectSpec spec;
  spec.type = type;
  spec.params = params;
  spec.robot = robot;
  spec.joint = joint;
  spec.where = kWhere;
  return spec;
}

// Expects MakeEffect(spec) to throw an InputError whose message contains `where` and every one
// of `parts`.
void ExpectInputError(const EffectSpec& spec, std::initializer_list<std::string> parts) {
  try {
    MakeEffect(spec);
    ADD_FAILURE() << "expected InputError for effect " << spec.type;
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.where(), kWhere);
    EXPECT_NE(what.find(kWhere), std::string::npos) << what;
    for (const std::string& part : parts) {
      EXPECT_NE(what.find(part), std::string::npos) << "'" << part << "' not in: " << what;
    }
  }
}

double SampleStd(const std::vector<double>& x, double* mean) {
  double sum = 0.0, sum2 = 0.0;
  for (double v : x) sum += v;
  *mean = sum / x.size();
  for (double v : x) sum2 += (v - *mean) * (v - *mean);
  return std::sqrt(sum2 / (x.size() - 1));
}

// One valid spec per registered type.
std::map<std::string, EffectSpec> ValidSpecs() {
  return {
      {"geometry_errors", Spec("geometry_errors", {{"sigma_length_mm", 0.1},
                                                   {"sigma_angle_deg", 0.02},
                                                   {"link3.alpha_deg", 0.05}})},
      {"thermal_growth", Spec("thermal_growth", {{"delta_T_K", 10.0}})},
      {"thermal_drift", Spec("thermal_drift", {{"delta_T_K", 8.0}, {"time_constant_s", 900}})},
      {"joint_compliance", Spec("joint_compliance", {{"stiffness_Nm_per_rad", 5e4}}, 0, 1)},
      {"transmission_error",
       Spec("transmission_error", {{"amplitude_deg", 0.01}, {"harmonic", 2}}, 1, 3)},
      {"backlash", Spec("backlash", {{"width_deg", 0.05}})},
      {"encoder_quantization", Spec("encoder_quantization", {{"counts_per_rev", 1 << 17}})},
      {"encoder_noise", Spec("encoder_noise", {{"sigma_deg", 0.001}}, 0)},
      {"image_noise", Spec("image_noise", {{"sigma_levels", 2.0}})},
      {"mount_deflection", Spec("mount_deflection", {{"deflection_x_mm", 0.04}}, 1)},
      {"lateral_compliance", Spec("lateral_compliance", {{"stiffness_Nm_per_rad", 2e5}}, 1, 1)},
      {"base_compliance", Spec("base_compliance", {}, 1)},
      {"axis_wobble",
       Spec("axis_wobble", {{"amplitude_rad", 5e-5}, {"order", 3}, {"phase_rad", 0.2}}, 1, 0)},
  };
}

TEST(EffectRegistry, MakesEveryRegisteredTypeFromValidParams) {
  const std::map<std::string, EffectSpec> specs = ValidSpecs();
  const std::vector<std::string> types = EffectTypes();
  // The table above must cover the registry exactly, so a new effect needs a row here.
  EXPECT_EQ(std::set<std::string>(types.begin(), types.end()).size(), types.size());
  ASSERT_EQ(types.size(), specs.size());
  for (const std::string& type : types) {
    ASSERT_EQ(specs.count(type), 1u) << type << " has no valid spec in this test";
    const std::unique_ptr<Effect> effect = MakeEffect(specs.at(type));
    ASSERT_NE(effect, nullptr) << type;
    EXPECT_EQ(effect->spec().type, type);
    EXPECT_EQ(effect->spec().robot, specs.at(type).robot);
    EXPECT_EQ(effect->spec().joint, specs.at(type).joint);
  }
}

TEST(EffectRegistry, UnknownTypeListsTheKnownTypes) {
  std::vector<std::string> parts = {"\"gear_wear\""};
  for (const std::string& type : EffectTypes()) parts.push_back(type);
  try {
    MakeEffect(Spec("gear_wear", {}));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(kWhere), std::string::npos) << what;
    for (const std::string& part : parts) EXPECT_NE(what.find(part), std::string::npos) << what;
  }
}

TEST(EffectRegistry, UnknownParameterIsNamedWithTheAllowedKeys) {
  ExpectInputError(Spec("backlash", {{"widht_deg", 0.1}}),
                   {"backlash", "unknown parameter \"widht_deg\"", "allowed: width_deg"});
  ExpectInputError(Spec("transmission_error",
                        {{"amplitude_deg", 0.01}, {"harmonic", 1}, {"phase_rad", 0.1}}),
                   {"\"phase_rad\"", "amplitude_deg, harmonic, phase_deg"});
  // Keys exist for chains up to kMaxJoints = 12 joints (13 links); a six-axis robot refuses
  // link8 when the geometry is built (GeometryDeltaBeyondTheToolLinkIsRefused).
  ExpectInputError(Spec("geometry_errors", {{"link14.alpha_deg", 0.1}}),
                   {"\"link14.alpha_deg\"", "link<i>.<theta|alpha|beta>_deg"});
  ExpectInputError(Spec("geometry_errors", {{"link3.d_deg", 0.1}}), {"\"link3.d_deg\""});
}

TEST(EffectRegistry, MissingRequiredParameterIsNamed) {
  ExpectInputError(Spec("transmission_error", {{"amplitude_deg", 0.01}}),
                   {"transmission_error", "missing required parameter \"harmonic\""});
  ExpectInputError(Spec("backlash", {}), {"missing required parameter \"width_deg\""});
  ExpectInputError(Spec("thermal_growth", {{"coefficient_per_K", 2.3e-5}}),
                   {"missing required parameter \"delta_T_K\""});
  ExpectInputError(Spec("geometry_errors", {}), {"geometry_errors", "no parameters"});
}

TEST(EffectRegistry, OutOfRangeValuesAreNamed) {
  ExpectInputError(Spec("backlash", {{"width_deg", -0.1}}), {"width_deg = -0.1", "> 0"});
  ExpectInputError(Spec("transmission_error", {{"amplitude_deg", 0.01}, {"harmonic", 0}}),
                   {"harmonic = 0", "a whole number in [1, 1000]"});
  ExpectInputError(Spec("transmission_error", {{"amplitude_deg", 0.01}, {"harmonic", 1.5}}),
                   {"harmonic = 1.5", "whole number"});
  ExpectInputError(Spec("encoder_quantization", {{"counts_per_rev", 1000}}),
                   {"counts_per_rev = 1000", "[1024, 4294967296]"});
  ExpectInputError(Spec("encoder_noise", {{"sigma_deg", std::nan("")}}), {"sigma_deg = nan"});
  ExpectInputError(Spec("thermal_growth", {{"delta_T_K", 293.15}}),
                   {"delta_T_K = 293.15", "[-100, 100]"});
  ExpectInputError(Spec("image_noise", {{"sigma_levels", 0.0}}), {"sigma_levels = 0", "> 0"});
  ExpectInputError(Spec("backlash", {{"width_deg", 0.1}}, 0, 12), {"joint = 12", "0..11"});
  ExpectInputError(Spec("backlash", {{"width_deg", 0.1}}, 0, -2), {"joint = -2"});
  ExpectInputError(Spec("encoder_noise", {{"sigma_deg", 0.1}}, 2), {"robot = 2", "0..1"});
  ExpectInputError(Spec("geometry_errors", {{"sigma_angle_deg", 0.1}}, 0, 2),
                   {"geometry_errors", "joint = 2", "expected -1"});
  ExpectInputError(Spec("image_noise", {{"sigma_levels", 2.0}}, 0), {"image_noise", "robot = 0"});
}

// The three structural effects (issue 39): each bad key named with its value and range.
TEST(EffectRegistry, StructuralEffectsRefuseBadParametersNamingTheKey) {
  ExpectInputError(Spec("lateral_compliance", {{"stiffness_Nm_per_rad", 10.0}}, 1, 1),
                   {"lateral_compliance", "stiffness_Nm_per_rad = 10", "[1000, 1e+10]"});
  ExpectInputError(Spec("lateral_compliance", {{"stiffness_Nm_per_rad", std::nan("")}}, 1, 1),
                   {"stiffness_Nm_per_rad = nan"});
  ExpectInputError(Spec("lateral_compliance", {{"stiffnes_Nm_per_rad", 2e5}}, 1, 1),
                   {"unknown parameter \"stiffnes_Nm_per_rad\"", "allowed: stiffness_Nm_per_rad"});
  ExpectInputError(Spec("base_compliance", {{"stiffness_Nm_per_rad", -1e6}}, 1),
                   {"base_compliance", "stiffness_Nm_per_rad = -1000000"});
  ExpectInputError(Spec("base_compliance", {}, 1, 2),
                   {"base_compliance", "joint = 2", "expected -1"});
  ExpectInputError(Spec("axis_wobble", {{"amplitude_rad", 0.0}}, 1, 0),
                   {"axis_wobble", "amplitude_rad = 0", "> 0"});
  ExpectInputError(Spec("axis_wobble", {{"amplitude_rad", 0.02}}, 1, 0),
                   {"amplitude_rad = 0.02", "<= 0.01"});
  ExpectInputError(Spec("axis_wobble", {{"order", 0}}, 1, 0), {"order = 0", "whole number"});
  ExpectInputError(Spec("axis_wobble", {{"order", 2.5}}, 1, 0), {"order = 2.5", "whole number"});
  ExpectInputError(Spec("axis_wobble", {{"phase_rad", 7.0}}, 1, 0), {"phase_rad = 7"});
  ExpectInputError(Spec("axis_wobble", {{"phase_deg", 10.0}}, 1, 0),
                   {"unknown parameter \"phase_deg\"", "amplitude_rad, order, phase_rad"});
}

// A 3rd-order gear error (issue 39): the transmission error takes harmonic 3 and follows
// A sin(3 q + phase).
TEST(TransmissionError, TakesAThirdOrderGearError) {
  const auto effect = MakeEffect(Spec(
      "transmission_error", {{"amplitude_deg", 0.01}, {"harmonic", 3}, {"phase_deg", 20}}, 0, 1));
  const JointVector motor = (JointVector(6) << 0.0, 0.7, 0.0, 0.0, 0.0, 0.0).finished();
  JointVector offset = JointVector::Zero(6);
  effect->ApplyToTransmission(0, motor, JointVector::Zero(6), &offset);
  const double A = 0.01 * kPi / 180.0, phase = 20.0 * kPi / 180.0;
  // 1e-15 rad: the same double arithmetic up to rounding of the degree conversion.
  EXPECT_NEAR(offset(1), A * std::sin(3.0 * 0.7 + phase), 1e-15);
  EXPECT_EQ(offset(0), 0.0);
}

TEST(LateralCompliance, SetsTheTiltStiffnessOfOnlyTheNamedRobotAndJoint) {
  const auto effect =
      MakeEffect(Spec("lateral_compliance", {{"stiffness_Nm_per_rad", 3e5}}, 1, 2));
  StructureCompliance s0, s1;
  s0.joint_tilt_stiffness.assign(6, 0.0);
  s1.joint_tilt_stiffness.assign(6, 0.0);
  effect->ApplyToStructure(0, &s0);
  effect->ApplyToStructure(1, &s1);
  for (int j = 0; j < 6; ++j) {
    EXPECT_EQ(s0.joint_tilt_stiffness[j], 0.0) << j;
    EXPECT_EQ(s1.joint_tilt_stiffness[j], j == 2 ? 3e5 : 0.0) << j;  // copied values: exact
  }
  EXPECT_EQ(s1.base_tilt_stiffness, 0.0);
  // The documented default.
  StructureCompliance d;
  d.joint_tilt_stiffness.assign(6, 0.0);
  MakeEffect(Spec("lateral_compliance", {}, 0, 1))->ApplyToStructure(0, &d);
  EXPECT_EQ(d.joint_tilt_stiffness[1], 2e5);
}

TEST(BaseCompliance, SetsTheBaseStiffnessOfOnlyTheNamedRobot) {
  const auto effect = MakeEffect(Spec("base_compliance", {{"stiffness_Nm_per_rad", 4e6}}, 0));
  StructureCompliance s0, s1;
  effect->ApplyToStructure(0, &s0);
  effect->ApplyToStructure(1, &s1);
  EXPECT_EQ(s0.base_tilt_stiffness, 4e6);
  EXPECT_EQ(s1.base_tilt_stiffness, 0.0);
  EXPECT_TRUE(s0.joint_tilt_stiffness.empty());
}

TEST(AxisWobble, TiltCounterRotatesWithItsOrderOnOnlyTheNamedJoint) {
  const double A = 4e-5, h = 2, phase = 0.3;
  const auto effect = MakeEffect(
      Spec("axis_wobble", {{"amplitude_rad", A}, {"order", h}, {"phase_rad", phase}}, 1, 0));
  EXPECT_TRUE(effect->TiltsAxes(1));
  EXPECT_FALSE(effect->TiltsAxes(0));
  for (double q1 : {-1.2, 0.0, 0.5, 2.0}) {
    JointVector q = JointVector::Constant(6, 0.4);
    q(0) = q1;
    std::vector<Eigen::Vector2d> tilt(6, Eigen::Vector2d::Zero()), tilt0 = tilt;
    effect->AddAxisTilt(1, q, &tilt);
    effect->AddAxisTilt(0, q, &tilt0);
    // 1e-18 rad: the documented formula in the same double arithmetic, against 4e-5 rad.
    EXPECT_NEAR(tilt[0].x(), A * std::sin(h * q1 + phase), 1e-18) << q1;
    EXPECT_NEAR(tilt[0].y(), A * std::cos(h * q1 + phase), 1e-18) << q1;
    EXPECT_EQ(tilt[0].norm() > 0.9 * A, true);
    for (int j = 1; j < 6; ++j) EXPECT_EQ(tilt[j].norm(), 0.0) << j;
    for (int j = 0; j < 6; ++j) EXPECT_EQ(tilt0[j].norm(), 0.0) << j;
  }
  // The direction of the tilt in the parent turns by -h times the joint's rotation: a quarter
  // turn of the tilt's angle for dq = pi / (2 h), clockwise.
  JointVector qa = JointVector::Zero(6), qb = qa;
  qb(0) = kPi / (2 * h);
  std::vector<Eigen::Vector2d> ta(6, Eigen::Vector2d::Zero()), tb = ta;
  effect->AddAxisTilt(1, qa, &ta);
  effect->AddAxisTilt(1, qb, &tb);
  const double turn = std::atan2(ta[0].x() * tb[0].y() - ta[0].y() * tb[0].x(), ta[0].dot(tb[0]));
  EXPECT_NEAR(turn, -kPi / 2, 1e-12);  // rounding of atan2 on unit-scale ratios
  // Defaults: 5e-5 rad, order 2, phase 0.
  std::vector<Eigen::Vector2d> td(6, Eigen::Vector2d::Zero());
  MakeEffect(Spec("axis_wobble", {}, 0, 3))->AddAxisTilt(0, qb, &td);
  EXPECT_NEAR(td[3].x(), 5e-5 * std::sin(2 * qb(3)), 1e-18);
  EXPECT_NEAR(td[3].y(), 5e-5 * std::cos(2 * qb(3)), 1e-18);
}

TEST(TransmissionError, MatchesItsFormulaAtSeveralAngles) {
  const auto effect = MakeEffect(Spec(
      "transmission_error", {{"amplitude_deg", 0.02}, {"harmonic", 2}, {"phase_deg", 30}}, 0, 1));
  const double amplitude = DegToRad(0.02), phase = DegToRad(30.0);
  for (double q : {-3.0, -1.2, 0.0, 0.4, 1.7, 3.1}) {
    const JointVector motor = JointVector::Constant(6, q);
    JointVector offset = JointVector::Constant(6, 1e-3);  // the hook adds to what is there
    effect->ApplyToTransmission(0, motor, JointVector::Ones(6), &offset);
    // Same formula, same operations: only a few roundings of a ~1e-3 rad value can differ.
    EXPECT_NEAR(offset(1), 1e-3 + amplitude * std::sin(2.0 * q + phase), 1e-15) << q;
    for (int j : {0, 2, 3, 4, 5}) EXPECT_EQ(offset(j), 1e-3) << "joint " << j << " untouched";
    JointVector other = JointVector::Zero(6);
    effect->ApplyToTransmission(1, motor, JointVector::Ones(6), &other);
    EXPECT_TRUE(other.isZero(0.0)) << "robot 1 untouched";
  }
}

TEST(Backlash, LagsAgainstTheApproachDirectionAndIsZeroBeforeAnyMotion) {
  const auto effect = MakeEffect(Spec("backlash", {{"width_deg", 0.2}}));
  JointVector direction(6);
  direction << 1, -1, 0, 1, -1, 0;
  JointVector offset = JointVector::Zero(6);
  effect->ApplyToTransmission(1, JointVector::Constant(6, 0.5), direction, &offset);
  const double half = DegToRad(0.1);
  // -0.5 * width * direction is one or two roundings away from DegToRad(0.1).
  for (int j : {0, 3}) EXPECT_NEAR(offset(j), -half, 1e-17) << "moved positive: link lags below";
  for (int j : {1, 4}) EXPECT_NEAR(offset(j), half, 1e-17) << "moved negative: link lags above";
  for (int j : {2, 5}) EXPECT_EQ(offset(j), 0.0) << "never moved: no offset";
}

TEST(EncoderQuantization, RoundsToTheNearestCount) {
  const int counts = 4096;
  const double step = 2.0 * kPi / counts;
  const auto effect = MakeEffect(Spec("encoder_quantization", {{"counts_per_rev", counts}}));
  for (int k : {-2047, -3, -1, 0, 5, 2047}) {
    for (double fraction : {0.0, 0.3, 0.49, 0.51, 0.7}) {
      JointVector reading = JointVector::Constant(6, (k + fraction) * step);
      effect->ApplyToEncoder(0, &reading, nullptr);
      const double expected = (fraction < 0.5 ? k : k + 1) * step;
      // expected is computed as the effect does (n * step); 1e-14 rad allows a few ulps at pi.
      for (int j = 0; j < 6; ++j) EXPECT_NEAR(reading(j), expected, 1e-14);
    }
  }
  // With a joint given, only that joint is quantized.
  const auto joint3 =
      MakeEffect(Spec("encoder_quantization", {{"counts_per_rev", counts}}, -1, 3));
  JointVector reading = JointVector::Constant(6, 0.3 * step);
  joint3->ApplyToEncoder(1, &reading, nullptr);
  for (int j = 0; j < 6; ++j) EXPECT_EQ(reading(j), j == 3 ? 0.0 : 0.3 * step);
}

TEST(EncoderNoise, SampleStdMatchesSigma) {
  const double sigma = DegToRad(0.01);
  const auto effect = MakeEffect(Spec("encoder_noise", {{"sigma_deg", 0.01}}));
  std::mt19937_64 rng(7);
  const JointVector truth = JointVector::LinSpaced(6, -1.0, 1.0);
  std::vector<double> errors;
  for (int n = 0; n < 20000; ++n) {
    JointVector reading = truth;
    effect->ApplyToEncoder(n % 2, &reading, &rng);
    for (int j = 0; j < 6; ++j) errors.push_back(reading(j) - truth(j));
  }
  double mean = 0.0;
  const double sample_std = SampleStd(errors, &mean);
  // 120000 samples: the sample std's relative standard error is 1/sqrt(2N) = 0.2 %, so 2 %
  // is 10 standard errors; the mean's standard error is sigma/sqrt(N), 5 of them allowed.
  EXPECT_NEAR(sample_std / sigma, 1.0, 0.02);
  EXPECT_LT(std::abs(mean), 5.0 * sigma / std::sqrt(static_cast<double>(errors.size())));
}

TEST(GeometryErrors, GeometryDeltaBeyondTheToolLinkIsRefused) {
  // A six-axis arm has links 1..7 (7 = the tool link): a delta of link 8 names the robot.
  const auto effect = MakeEffect(Spec("geometry_errors", {{"link8.alpha_deg", 0.1}}));
  KinematicModel model = testing::ReinovoLikeModel();
  std::mt19937_64 rng(1);
  try {
    effect->ApplyToGeometry(0, &model, &rng);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("link8.alpha_deg"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("only 7 links"), std::string::npos) << e.what();
  }
}

TEST(GeometryErrors, ExplicitDeltaChangesExactlyTheNamedParameter) {
  const KinematicModel nominal = testing::ReinovoLikeModel();
  const auto effect = MakeEffect(
      Spec("geometry_errors", {{"link3.alpha_deg", 0.05}, {"link2.d_mm", -0.3}}));
  std::mt19937_64 rng(3);
  const std::mt19937_64 rng_before = rng;
  KinematicModel model = nominal;
  effect->ApplyToGeometry(0, &model, &rng);
  EXPECT_TRUE(rng == rng_before) << "no sigma given: no random draws";
  const ParameterVector before = GetParameters(nominal), after = GetParameters(model);
  const int alpha3 = ParameterIndex(3, DhParameter::kAlpha);
  const int d2 = ParameterIndex(2, DhParameter::kD);
  // One addition each: the difference equals the converted delta up to one rounding of the sum.
  EXPECT_NEAR(after(alpha3) - before(alpha3), DegToRad(0.05), 1e-15);
  EXPECT_NEAR(after(d2) - before(d2), -0.3e-3, 1e-15);
  for (int i = 0; i < 35; ++i) {
    // Adding an exact 0.0 leaves every other parameter bit-identical.
    if (i == alpha3 || i == d2) continue;
    EXPECT_EQ(after(i), before(i)) << ParameterName("r1", i);
  }
}

TEST(GeometryErrors, RandomSigmaGivesMatchingSampleStd) {
  const KinematicModel nominal = testing::ReinovoLikeModel();
  const double sigma_length = 0.1e-3, sigma_angle = DegToRad(0.05);
  const auto effect = MakeEffect(
      Spec("geometry_errors", {{"sigma_length_mm", 0.1}, {"sigma_angle_deg", 0.05}}));
  std::mt19937_64 rng(11);
  const ParameterVector p0 = GetParameters(nominal);
  std::vector<double> lengths, angles;
  for (int n = 0; n < 2000; ++n) {
    KinematicModel model = nominal;
    effect->ApplyToGeometry(n % 2, &model, &rng);
    const ParameterVector dp = GetParameters(model) - p0;
    for (int i = 0; i < 35; ++i) {
      (IsLengthParameter(i) ? lengths : angles).push_back(dp(i));
    }
  }
  ASSERT_EQ(lengths.size(), 2000u * 14u);  // d and a of 7 links
  ASSERT_EQ(angles.size(), 2000u * 21u);   // theta, alpha, beta of 7 links
  double mean_l = 0.0, mean_a = 0.0;
  const double std_l = SampleStd(lengths, &mean_l), std_a = SampleStd(angles, &mean_a);
  // 28000 and 42000 samples: relative standard error of the std <= 0.42 %; 3 % is > 7 of them.
  EXPECT_NEAR(std_l / sigma_length, 1.0, 0.03);
  EXPECT_NEAR(std_a / sigma_angle, 1.0, 0.03);
  // Zero mean within 5 standard errors sigma/sqrt(N).
  EXPECT_LT(std::abs(mean_l), 5.0 * sigma_length / std::sqrt(28000.0));
  EXPECT_LT(std::abs(mean_a), 5.0 * sigma_angle / std::sqrt(42000.0));
}

TEST(ThermalDrift, WarmsUpWithItsTimeConstantAndOnlyOnItsRobot) {
  const auto effect = MakeEffect(Spec("thermal_drift", {{"coefficient_per_K", 2.3e-5},
                                                        {"delta_T_K", 10.0},
                                                        {"time_constant_s", 600.0}}, 1));
  EXPECT_TRUE(effect->DriftsLengths(1));
  EXPECT_FALSE(effect->DriftsLengths(0));
  EXPECT_EQ(effect->LengthScaleAt(1, 0.0), 1.0);  // the static geometry is the start
  // One time constant: 1 - 1/e of the final growth 2.3e-4; 1e-15 is a few ulps of 1.
  EXPECT_NEAR(effect->LengthScaleAt(1, 600.0), 1.0 + 2.3e-4 * (1.0 - std::exp(-1.0)), 1e-15);
  EXPECT_NEAR(effect->LengthScaleAt(1, 1e6), 1.0 + 2.3e-4, 1e-15);  // settled
  EXPECT_EQ(effect->LengthScaleAt(0, 600.0), 1.0);
  // The temperature its sensor sees follows the same curve: 10 K (1 - 1/e) at one time
  // constant, 10 K settled, none at the start or on the other robot (1e-12 K: rounding).
  EXPECT_EQ(effect->TemperatureDeltaAt(1, 0.0), 0.0);
  EXPECT_NEAR(effect->TemperatureDeltaAt(1, 600.0), 10.0 * (1.0 - std::exp(-1.0)), 1e-12);
  EXPECT_NEAR(effect->TemperatureDeltaAt(1, 1e6), 10.0, 1e-12);
  EXPECT_EQ(effect->TemperatureDeltaAt(0, 600.0), 0.0);
  // The static geometry is untouched (the twin moves its bodies as its clock runs).
  KinematicModel model = testing::ReinovoLikeModel();
  const KinematicModel before = model;
  effect->ApplyToGeometry(1, &model, nullptr);
  EXPECT_EQ(model.links[2].dh.a, before.links[2].dh.a);
  // Defaults: steel, 5 K, 30 min.
  const auto defaults = MakeEffect(Spec("thermal_drift", {}));
  EXPECT_NEAR(defaults->LengthScaleAt(0, 1800.0), 1.0 + 6e-5 * (1.0 - std::exp(-1.0)), 1e-15);
  ExpectInputError(Spec("thermal_drift", {{"time_constant_s", 1.0}}), {"time_constant_s"});
  ExpectInputError(Spec("thermal_drift", {{"delta_T_K", 300.0}}), {"delta_T_K"});
  ExpectInputError(Spec("thermal_drift", {{"delta_T_K", 5.0}}, 0, 2), {"every link"});
}

TEST(ThermalGrowth, ScalesLengthsAndNotAngles) {
  const KinematicModel nominal = testing::ReinovoLikeModel();
  const auto effect =
      MakeEffect(Spec("thermal_growth", {{"coefficient_per_K", 2.3e-5}, {"delta_T_K", 15.0}}));
  KinematicModel model = nominal;
  effect->ApplyToGeometry(1, &model, nullptr);
  const double scale = 1.0 + 2.3e-5 * 15.0;
  for (int i = 0; i < 7; ++i) {
    const DhParameters &a = nominal.links[i].dh, &b = model.links[i].dh;
    // Same single multiplication as the effect; 1e-15 m is ~10 ulps of a length < 0.5 m.
    EXPECT_NEAR(b.d, a.d * scale, 1e-15) << "link " << i + 1;
    EXPECT_NEAR(b.a, a.a * scale, 1e-15) << "link " << i + 1;
    EXPECT_EQ(b.theta_offset, a.theta_offset);  // untouched: bit-identical
    EXPECT_EQ(b.alpha, a.alpha);
    EXPECT_EQ(b.beta, a.beta);
  }
  // The arm stands at its temperature change all the time (what a sensor on it reads).
  EXPECT_EQ(effect->TemperatureDeltaAt(1, 0.0), 15.0);
  EXPECT_EQ(effect->TemperatureDeltaAt(0, 1e4), 15.0);  // robot -1: both
  // The default coefficient (steel, 1.2e-5 /K) applies when none is given.
  KinematicModel steel = nominal;
  MakeEffect(Spec("thermal_growth", {{"delta_T_K", 10.0}}))->ApplyToGeometry(0, &steel, nullptr);
  EXPECT_NEAR(steel.links[1].dh.a, nominal.links[1].dh.a * (1.0 + 1.2e-5 * 10.0), 1e-15);
}

TEST(JointCompliance, SetsTheDriveOfOnlyTheNamedJoint) {
  const auto effect =
      MakeEffect(Spec("joint_compliance", {{"stiffness_Nm_per_rad", 5e4}}, -1, 2));
  std::vector<JointDrive> drives(6);
  for (JointDrive& d : drives) d.stiffness = 1e5;
  effect->ApplyToDrive(0, &drives);
  for (int j = 0; j < 6; ++j) {
    EXPECT_EQ(drives[j].stiffness, j == 2 ? 5e4 : 1e5) << j;  // copied values: exact
    EXPECT_EQ(drives[j].gravity_feedforward, j != 2) << j;
  }
}

TEST(EffectFilter, RobotOneOnlyLeavesRobotZeroUntouched) {
  const KinematicModel nominal = testing::ReinovoLikeModel();
  const auto geometry = MakeEffect(Spec("geometry_errors", {{"sigma_angle_deg", 0.1}}, 1));
  std::mt19937_64 rng(5);
  const std::mt19937_64 rng_before = rng;
  KinematicModel model0 = nominal, model1 = nominal;
  geometry->ApplyToGeometry(0, &model0, &rng);
  EXPECT_TRUE(GetParameters(model0) == GetParameters(nominal));  // untouched: bit-identical
  EXPECT_TRUE(rng == rng_before) << "no draws for a robot it does not act on";
  geometry->ApplyToGeometry(1, &model1, &rng);
  EXPECT_FALSE(GetParameters(model1) == GetParameters(nominal));

  const auto noise = MakeEffect(Spec("encoder_noise", {{"sigma_deg", 0.1}}, 1));
  JointVector reading0 = JointVector::Constant(6, 0.25), reading1 = reading0;
  noise->ApplyToEncoder(0, &reading0, &rng);
  noise->ApplyToEncoder(1, &reading1, &rng);
  EXPECT_TRUE(reading0 == JointVector::Constant(6, 0.25));
  EXPECT_FALSE(reading1 == JointVector::Constant(6, 0.25));

  const auto compliance =
      MakeEffect(Spec("joint_compliance", {{"stiffness_Nm_per_rad", 3e4}}, 1));
  std::vector<JointDrive> drives0(6), drives1(6);
  compliance->ApplyToDrive(0, &drives0);
  compliance->ApplyToDrive(1, &drives1);
  for (int j = 0; j < 6; ++j) {
    EXPECT_EQ(drives0[j].stiffness, 0.0);
    EXPECT_TRUE(drives0[j].gravity_feedforward);
    EXPECT_EQ(drives1[j].stiffness, 3e4);
    EXPECT_FALSE(drives1[j].gravity_feedforward);
  }
}

TEST(Effect, HooksAnEffectDoesNotUseChangeNothing) {
  const KinematicModel nominal = testing::ReinovoLikeModel();
  const auto backlash = MakeEffect(Spec("backlash", {{"width_deg", 0.1}}));
  std::mt19937_64 rng(1);
  KinematicModel model = nominal;
  backlash->ApplyToGeometry(0, &model, &rng);
  EXPECT_TRUE(GetParameters(model) == GetParameters(nominal));
  JointVector reading = JointVector::Constant(6, 0.5);
  backlash->ApplyToEncoder(0, &reading, &rng);
  EXPECT_TRUE(reading == JointVector::Constant(6, 0.5));
  std::vector<JointDrive> drives(6);
  backlash->ApplyToDrive(0, &drives);
  EXPECT_EQ(drives[0].stiffness, 0.0);
  StructureCompliance structure;
  structure.joint_tilt_stiffness.assign(6, 0.0);
  backlash->ApplyToStructure(0, &structure);
  EXPECT_EQ(structure.base_tilt_stiffness, 0.0);
  EXPECT_EQ(structure.joint_tilt_stiffness, std::vector<double>(6, 0.0));
  EXPECT_FALSE(backlash->TiltsAxes(0));
  std::vector<Eigen::Vector2d> tilt(6, Eigen::Vector2d::Zero());
  backlash->AddAxisTilt(0, JointVector::Constant(6, 0.5), &tilt);
  EXPECT_EQ(tilt[0].norm(), 0.0);
  const cv::Mat original(4, 4, CV_8UC3, cv::Scalar(10, 20, 30));
  cv::Mat image = original.clone();
  backlash->ApplyToImage(&image, &rng);
  EXPECT_EQ(cv::norm(image, original, cv::NORM_INF), 0.0);
  EXPECT_TRUE(rng == std::mt19937_64(1)) << "no hook drew from the rng";
}

TEST(ImageNoise, AddsNoiseOfSigmaSeededFromTheRng) {
  const auto effect = MakeEffect(Spec("image_noise", {{"sigma_levels", 5.0}}));
  const cv::Mat grey(200, 200, CV_8UC3, cv::Scalar(128, 128, 128));
  std::mt19937_64 rng_a(9), rng_b(9);
  cv::Mat a = grey.clone(), b = grey.clone(), c = grey.clone();
  effect->ApplyToImage(&a, &rng_a);
  effect->ApplyToImage(&b, &rng_b);
  effect->ApplyToImage(&c, &rng_a);  // the next seed from the same rng
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << "same rng state, same image";
  EXPECT_GT(cv::norm(a, c, cv::NORM_INF), 0.0) << "each image draws a new seed";
  cv::Mat diff;
  cv::subtract(a, grey, diff, cv::noArray(), CV_64F);
  cv::Scalar mean, stddev;
  cv::meanStdDev(diff.reshape(1), mean, stddev);
  // 120000 samples, rounded to whole levels (adds 1/12 level^2 of variance, +0.2 % at
  // sigma 5), no saturation at 128 +- 5 sigma: 5 % covers rounding and sampling error.
  EXPECT_NEAR(stddev[0] / 5.0, 1.0, 0.05);
  EXPECT_LT(std::abs(mean[0]), 0.1);  // 5 standard errors 5/sqrt(120000) = 0.014, plus rounding
}

}  // namespace
}  // namespace twin
