#include "bench/io/model_yaml.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "text_edit.h"

namespace twin {
namespace {

using testing::LineOf;
using testing::ReadFile;
using testing::Replaced;

const std::string kR1Path = std::string(TWIN_SOURCE_DIR) + "/models/reinovo_r1.yaml";
const std::string kR2Path = std::string(TWIN_SOURCE_DIR) + "/models/reinovo_r2.yaml";
const std::string kSource = "models/test.yaml";

// Parsing and degree conversion are exact to a few ulp of values of order 1..300.
constexpr double kExact = 1e-12;

std::string R1Text() { return ReadFile(kR1Path); }

/// "models/test.yaml:<line>", the location prefix the parser must report.
std::string At(int line) { return kSource + ":" + std::to_string(line); }

/// The what() of the InputError that parsing text throws (a test failure if none).
std::string ParseError(const std::string& text) {
  try {
    ParseModelYaml(text, kSource);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an InputError";
  return "";
}

::testing::AssertionResult Contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << text << "' lacks '" << part << "'";
}

void ExpectTransformNear(const Transform& a, const Transform& b, double tol) {
  EXPECT_LE((a.matrix() - b.matrix()).cwiseAbs().maxCoeff(), tol) << a.matrix() << "\nvs\n"
                                                                  << b.matrix();
}

void ExpectModelsNear(const KinematicModel& a, const KinematicModel& b, double tol) {
  EXPECT_EQ(a.name, b.name);
  ExpectTransformNear(a.X_BL0, b.X_BL0, tol);
  ExpectTransformNear(a.X_LtE, b.X_LtE, tol);
  for (int i = 0; i < 7; ++i) {
    SCOPED_TRACE("link " + std::to_string(i + 1));
    const Link& la = a.links[i];
    const Link& lb = b.links[i];
    EXPECT_EQ(la.name, lb.name);
    EXPECT_NEAR(la.dh.theta_offset, lb.dh.theta_offset, tol);
    EXPECT_NEAR(la.dh.d, lb.dh.d, tol);
    EXPECT_NEAR(la.dh.a, lb.dh.a, tol);
    EXPECT_NEAR(la.dh.alpha, lb.dh.alpha, tol);
    EXPECT_NEAR(la.dh.beta, lb.dh.beta, tol);
    if (i < 6) {
      EXPECT_NEAR(la.limits.lower, lb.limits.lower, tol);
      EXPECT_NEAR(la.limits.upper, lb.limits.upper, tol);
    }
    EXPECT_NEAR(la.inertia.mass, lb.inertia.mass, tol);
    EXPECT_LE((la.inertia.p_LiCom - lb.inertia.p_LiCom).cwiseAbs().maxCoeff(), tol);
    EXPECT_LE((la.inertia.I_Com - lb.inertia.I_Com).cwiseAbs().maxCoeff(), tol);
  }
}

Matrix3 RandomRotation(std::mt19937* rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Eigen::Quaterniond(n(*rng), n(*rng), n(*rng), n(*rng)).normalized().toRotationMatrix();
}

Matrix3 Rpy(double r, double p, double y) {
  return (Eigen::AngleAxisd(y, Vector3::UnitZ()) * Eigen::AngleAxisd(p, Vector3::UnitY()) *
          Eigen::AngleAxisd(r, Vector3::UnitX()))
      .toRotationMatrix();
}

// ---- Loading the shipped models ----

TEST(ModelYamlTest, LoadsReinovoR1) {
  const KinematicModel m = LoadModelYaml(kR1Path);
  EXPECT_EQ(m.name, "r1");
  ASSERT_EQ(m.links.size(), static_cast<std::size_t>(7));  // 6 jointed + tool
  EXPECT_EQ(m.links[0].name, "link1");
  EXPECT_EQ(m.links[5].name, "link6");
  EXPECT_NEAR(m.links[1].dh.theta_offset, kPi / 2, kExact);
  EXPECT_NEAR(m.links[0].dh.alpha, kPi / 2, kExact);
  EXPECT_NEAR(m.links[0].dh.d, 0.1365, kExact);
  EXPECT_NEAR(m.links[5].dh.d, 0.1215, kExact);
  EXPECT_NEAR(m.links[0].limits.lower, DegToRad(-170), kExact);
  EXPECT_NEAR(m.links[5].limits.upper, DegToRad(270), kExact);
  EXPECT_NEAR(m.links[0].inertia.mass, 7.0, kExact);
  EXPECT_NEAR(m.links[0].inertia.p_LiCom.y(), -0.0683, kExact);
  EXPECT_NEAR(m.links[0].inertia.I_Com(0, 1), -0.00262, kExact);
  EXPECT_NEAR(m.links[0].inertia.I_Com(1, 0), -0.00262, kExact);  // symmetric fill
  EXPECT_EQ(m.tool().name, "tool");
  EXPECT_NEAR(m.tool().dh.theta_offset, -kPi / 2, kExact);
  EXPECT_NEAR(m.tool().dh.a, 0.060, kExact);
  EXPECT_EQ(m.tool().inertia.mass, 0.0);  // optional for the tool, default exactly 0
  EXPECT_TRUE(m.X_BL0.matrix().isIdentity(0.0));  // absent base: exactly identity
  EXPECT_TRUE(m.X_LtE.matrix().isIdentity(0.0));
}

TEST(ModelYamlTest, LoadsReinovoR2) {
  const KinematicModel m = LoadModelYaml(kR2Path);
  EXPECT_EQ(m.name, "r2");
  EXPECT_NEAR(m.links[1].dh.theta_offset, kPi / 2, kExact);
  EXPECT_NEAR(m.links[5].dh.d, 0.131, kExact);
  EXPECT_NEAR(m.tool().dh.theta_offset, -kPi / 2, kExact);
}

TEST(ModelYamlTest, RadiansAreTakenAsIs) {
  const std::string text =
      "robot:\n  name: r\n  angle_unit: rad\n  links:\n"
      "    - {name: l1, theta_offset: 1.5, d: 0.1, a: 0, alpha: 0.5, beta: 0, limits: [-3, 3],\n"
      "       mass: 1, com: [0, 0, 0], inertia: [0.01, 0.01, 0.01, 0, 0, 0]}\n"
      "  tool: {name: tool, theta_offset: 0, d: 0, a: 0, alpha: 0, beta: 0}\n";
  const KinematicModel m = ParseModelYaml(text, kSource);
  EXPECT_NEAR(m.links[0].dh.theta_offset, 1.5, kExact);
  EXPECT_NEAR(m.links[0].dh.alpha, 0.5, kExact);
  EXPECT_NEAR(m.links[0].limits.upper, 3.0, kExact);
}

TEST(ModelYamlTest, BaseAndEndUseUrdfRollPitchYaw) {
  std::string text = R1Text() +
                     "  base: {xyz: [0.1, 0, 0.2], rpy: [0, 0, 90]}\n"
                     "  end:\n"
                     "    rpy: [90, 90, 0]\n";
  const KinematicModel m = ParseModelYaml(text, kSource);
  // Yaw 90 deg about z maps x to y, then the offset is added.
  EXPECT_LE((m.X_BL0 * Vector3::UnitX() - Vector3(0.1, 1.0, 0.2)).norm(), kExact);
  // R = Rz(0) Ry(90) Rx(90): y -> z by Rx, then z -> x by Ry. The other order gives z.
  EXPECT_LE((m.X_LtE.linear() * Vector3::UnitY() - Vector3::UnitX()).norm(), kExact);
  EXPECT_LE(m.X_LtE.translation().norm(), 0.0);  // absent xyz: exactly zero
}

// ---- Round trip ----

KinematicModel PerturbedModel() {
  KinematicModel m = LoadModelYaml(kR1Path);
  m.name = "arm #1: left";  // needs quoting to read back
  m.links[1].dh.beta = 0.0123456789012345;
  m.links[2].dh.alpha = kPi / 2 + 1.234e-4;
  m.links[3].dh.theta_offset = -0.1 / 3.0;
  m.links[4].dh.d = 1e-7 / 3.0;
  m.links[0].limits.lower = -2.9670597283903604;
  Link& tool = m.links[6];
  tool.dh.beta = -0.02;
  tool.inertia.mass = 0.35;
  tool.inertia.p_LiCom = Vector3(0.01, -0.02, 0.045);
  tool.inertia.I_Com << 1.1e-3, 1e-5, -2e-5, 1e-5, 1.3e-3, 3e-6, -2e-5, 3e-6, 1.7e-3;
  m.X_BL0.translation() = Vector3(0.5, -0.25, 0.1);
  m.X_BL0.linear() = Rpy(0.1, -0.2, 2.5);
  m.X_LtE.translation() = Vector3(0.0, 0.0, 0.05);
  m.X_LtE.linear() = Rpy(-3.0, 1.2, -0.4);
  return m;
}

TEST(ModelYamlTest, RoundTripReproducesModel) {
  const KinematicModel m = PerturbedModel();
  const std::string yaml = ModelToYaml(m);
  const KinematicModel back = ParseModelYaml(yaml, "roundtrip");
  // Numbers are written in shortest exact form; only rad -> deg -> rad and rpy -> R cost a
  // few ulp, far below 1e-12.
  ExpectModelsNear(m, back, kExact);
  EXPECT_NE(yaml.find("angle_unit: deg"), std::string::npos);
}

TEST(ModelYamlTest, RoundTripOfShippedModelOmitsIdentityTransforms) {
  const KinematicModel m = LoadModelYaml(kR2Path);
  const std::string yaml = ModelToYaml(m);
  EXPECT_EQ(yaml.find("base:"), std::string::npos);
  EXPECT_EQ(yaml.find("end:"), std::string::npos);
  // Degrees come out as the file wrote them, not as 119.99999999999999.
  EXPECT_NE(yaml.find("limits: [-120, 120]"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("theta_offset: -90"), std::string::npos) << yaml;
  ExpectModelsNear(m, ParseModelYaml(yaml, "roundtrip"), kExact);  // as above
}

TEST(ModelYamlTest, RoundTripRotationsIncludingGimbalLock) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  std::vector<Matrix3> rotations;
  for (int i = 0; i < 200; ++i) rotations.push_back(RandomRotation(&rng));
  // Pitch at and next to +-90 deg, where roll and yaw share one axis.
  for (double pitch : {kPi / 2, -kPi / 2, kPi / 2 - 1e-7, -kPi / 2 + 1e-9, kPi / 2 + 1e-12}) {
    for (int i = 0; i < 20; ++i) rotations.push_back(Rpy(angle(rng), pitch, angle(rng)));
  }
  KinematicModel m = LoadModelYaml(kR1Path);
  for (const Matrix3& R : rotations) {
    m.X_BL0.linear() = R;
    m.X_LtE.linear() = R.transpose();
    const KinematicModel back = ParseModelYaml(ModelToYaml(m), "roundtrip");
    // The writer takes yaw first and reads roll and pitch from Rz(-yaw) R, so the three angles
    // reproduce R even where yaw alone is ill-conditioned (pitch = +-90 deg); what remains is
    // the degree conversion and trigonometry, a few ulp (about 1.3e-15 measured over 2000
    // such rotations), so 1e-12 leaves a wide margin.
    ExpectTransformNear(m.X_BL0, back.X_BL0, kExact);
    ExpectTransformNear(m.X_LtE, back.X_LtE, kExact);
  }
}

// ---- Bad input: each message names where and what was expected ----

TEST(ModelYamlErrorTest, MalformedYamlNamesSourceAndLine) {
  const std::string text = Replaced(R1Text(), "limits: [-170, 170]", "limits: [-170, 170");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, "malformed YAML"));
  EXPECT_TRUE(Contains(msg, "end of sequence flow not found"));  // yaml-cpp's own message
  // yaml-cpp reports where it notices the missing bracket: that line or the next one.
  const int line = LineOf(text, "limits: [-170, 170");
  EXPECT_TRUE(Contains(msg, At(line)) || Contains(msg, At(line + 1))) << msg;
}

TEST(ModelYamlErrorTest, UnknownKeyNamesKeyAndAllowedKeys) {
  const std::string text = Replaced(R1Text(), "mass: 7.5", "masss: 7.5");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "masss")) + " robot.links[1].masss"));
  EXPECT_TRUE(Contains(msg, "unknown key 'masss' (allowed: name, theta_offset, d, a, alpha, "
                            "beta, limits, mass, com, inertia)"));
}

TEST(ModelYamlErrorTest, UnknownTopLevelKey) {
  const std::string msg = ParseError(R1Text() + "extra: 1\n");
  EXPECT_TRUE(Contains(msg, "unknown key 'extra' (allowed: robot)"));
}

TEST(ModelYamlErrorTest, LimitsAreNotAllowedInTool) {
  const std::string text =
      Replaced(R1Text(), "    name: tool\n", "    name: tool\n    limits: [-1, 1]\n");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, "robot.tool.limits"));
  EXPECT_TRUE(Contains(msg, "unknown key 'limits'"));
}

TEST(ModelYamlErrorTest, MissingKeyIsNamed) {
  const std::string text = Replaced(R1Text(), "      mass: 7.5\n", "");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "name: link2")) + " robot.links[1]"));
  EXPECT_TRUE(Contains(msg, "missing required key 'mass'"));
}

TEST(ModelYamlTest, FiveLinksMakeAFiveJointChain) {
  std::string text = R1Text();
  const std::size_t begin = text.find("    - name: link6");
  const std::size_t end = text.find("  tool:");
  ASSERT_NE(begin, std::string::npos);
  ASSERT_NE(end, std::string::npos);
  text.erase(begin, end - begin);
  const KinematicModel m = ParseModelYaml(text, "five.yaml");
  EXPECT_EQ(m.num_joints(), 5);
  EXPECT_EQ(m.num_parameters(), 30);
  EXPECT_EQ(m.tool().name, "tool");
}

TEST(ModelYamlErrorTest, EmptyOrTooLongLinkListsAreRejected) {
  std::string text = R1Text();
  const std::string key = "  links:\n";
  const std::size_t begin = text.find(key) + key.size();
  const std::size_t end = text.find("  tool:");
  ASSERT_NE(end, std::string::npos);
  const std::string links = text.substr(begin, end - begin);
  std::string empty = text;
  empty.replace(begin - key.size(), end - begin + key.size(), "  links: []\n");
  EXPECT_TRUE(Contains(ParseError(empty), "expected a list of 1 to 12 links (one per joint), "
                                          "got 0 entries"));
  std::string thirteen = text;
  thirteen.insert(end, links + links.substr(0, links.find("    - name: link2")));  // 6 + 6 + 1
  EXPECT_TRUE(Contains(ParseError(thirteen), "got 13 entries"));
}

TEST(ModelYamlErrorTest, NonNumericValueNamesPathAndText) {
  const std::string text = Replaced(R1Text(), "d: 0.1215", "d: abc");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "d: abc")) + " robot.links[5].d"));
  EXPECT_TRUE(Contains(msg, "expected a number, got 'abc'"));
}

TEST(ModelYamlErrorTest, NonNumericListItemNamesIndex) {
  const std::string text = Replaced(R1Text(), "com: [-0.05, -0.0683, 0.0]", "com: [-0.05, x, 0]");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, "robot.links[0].com[1]"));
  EXPECT_TRUE(Contains(msg, "expected a number, got 'x'"));
}

TEST(ModelYamlErrorTest, WrongListLength) {
  const std::string msg = ParseError(Replaced(R1Text(), "com: [-0.145, 0.0, 0.0]", "com: [1, 2]"));
  EXPECT_TRUE(Contains(msg, "robot.links[1].com"));
  EXPECT_TRUE(Contains(msg, "expected a sequence of 3 numbers, got a sequence of 2 items"));
}

TEST(ModelYamlErrorTest, LowerLimitMustBeBelowUpper) {
  const std::string text = Replaced(R1Text(), "limits: [-120, 120]", "limits: [120, -120]");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "[120, -120]")) + " robot.links[1].limits"));
  EXPECT_TRUE(Contains(msg, "lower limit 120 must be below upper limit -120"));
  const std::string equal = ParseError(Replaced(R1Text(), "limits: [-120, 120]", "limits: [5, 5]"));
  EXPECT_TRUE(Contains(equal, "lower limit 5 must be below upper limit 5"));
}

TEST(ModelYamlErrorTest, InvalidAngleUnit) {
  const std::string text = Replaced(R1Text(), "angle_unit: deg", "angle_unit: grad");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "grad")) + " robot.angle_unit"));
  EXPECT_TRUE(Contains(msg, "angle_unit must be 'deg' or 'rad', got 'grad'"));
}

TEST(ModelYamlErrorTest, NegativeMass) {
  const std::string text = Replaced(R1Text(), "mass: 4.5", "mass: -4.5");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "-4.5")) + " robot.links[2].mass"));
  EXPECT_TRUE(Contains(msg, "mass must be in [0, 10000] kg"));
  EXPECT_TRUE(Contains(msg, "got -4.5 kg"));
}

TEST(ModelYamlErrorTest, UnphysicalInertiaNamesLineAndKey) {
  const std::string text = Replaced(R1Text(), "[0.02598, 0.02432, 0.0279,",
                                    "[1.0, 0.02432, 0.0279,");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "[1.0, 0.02432")) + " robot.links[0].inertia"));
  EXPECT_TRUE(Contains(msg, "inertia tensor is not physical"));
  EXPECT_TRUE(Contains(msg, "triangle inequality"));
}

// Plausibility limits (bench/io/plausibility.h): finite but absurd values are refused at the
// line and key with the limit.
TEST(ModelYamlErrorTest, AbsurdFiniteValuesAreRefusedWithTheLimit) {
  struct Case {
    std::string from, to, key, expected;
  };
  const Case cases[] = {
      {"a: 0.290", "a: 1e308", "robot.links[1].a", "within +-10 m"},
      {"a: 0.290", "a: 1000000", "robot.links[1].a", "millimetres read as metres"},
      {"d: 0.310", "d: -12", "robot.links[3].d", "within +-10 m"},
      {"alpha: -90", "alpha: -900", "robot.links[3].alpha", "within one turn, +-360 deg"},
      {"limits: [-270, 270]", "limits: [-270, 7200]", "robot.links[5].limits[1]",
       "within two turns, +-720 deg"},
      {"mass: 7.5", "mass: 1e6", "robot.links[1].mass", "[0, 10000] kg"},
      {"com: [-0.145, 0.0, 0.0]", "com: [-14.5, 0.0, 0.0]", "robot.links[1].com[0]",
       "within +-10 m"},
      {"inertia: [0.01838, 0.06175, 0.06175, 0.0, 0.0, 0.0]",
       "inertia: [18380, 61750, 61750, 0.0, 0.0, 0.0]", "robot.links[1].inertia",
       "not plausible"},
      {"inertia: [0.01838, 0.06175, 0.06175, 0.0, 0.0, 0.0]",
       "inertia: [-0.01838, 0.06175, 0.06175, 0.0, 0.0, 0.0]", "robot.links[1].inertia",
       "principal moments must be > 0"},
  };
  for (const Case& c : cases) {
    const std::string text = Replaced(R1Text(), c.from, c.to);
    const std::string msg = ParseError(text);
    EXPECT_TRUE(Contains(msg, At(LineOf(text, c.to)) + " " + c.key)) << c.to;
    EXPECT_TRUE(Contains(msg, c.expected)) << c.to;
  }
  // Radians: 90 in a rad file is 14 turns, degrees written as radians.
  const std::string rad = Replaced(R1Text(), "angle_unit: deg", "angle_unit: rad");
  EXPECT_TRUE(Contains(ParseError(rad), "degrees written as radians"));
  // NaN is refused as a non-finite number wherever it appears.
  EXPECT_TRUE(Contains(ParseError(Replaced(R1Text(), "mass: 7.5", "mass: .nan")),
                       "expected a finite number"));
}

TEST(ModelYaml, SevenJointArmIsPlausible) {
  // A redundant arm: link 4 repeated (lengths within the limits); the limits allow 1..12 joints.
  const std::string text = R1Text();
  const std::size_t from = text.find("    - name: link4");
  const std::size_t to = text.find("    - name: link5");
  ASSERT_NE(from, std::string::npos);
  std::string seven = text;
  std::string link = text.substr(from, to - from);
  link.replace(link.find("link4"), 5, "link4b");
  seven.insert(to, link);
  const KinematicModel m = ParseModelYaml(seven, kSource);
  EXPECT_EQ(m.num_joints(), 7);
}

TEST(ModelYamlErrorTest, MissingFileNamesPath) {
  const std::string path = "/nonexistent/dir/model.yaml";
  try {
    LoadModelYaml(path);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_TRUE(Contains(e.what(), path));
    EXPECT_TRUE(Contains(e.what(), "cannot open file"));
  }
}

TEST(ModelYamlErrorTest, DirectoryIsNotReadable) {
  const std::string path = std::string(TWIN_SOURCE_DIR) + "/models";
  try {
    LoadModelYaml(path);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_TRUE(Contains(e.what(), path));
    EXPECT_TRUE(Contains(e.what(), "cannot"));
  }
}

TEST(ModelYamlErrorTest, EmptyTextNeedsRobot) {
  const std::string msg = ParseError("");
  EXPECT_TRUE(Contains(msg, kSource));
  EXPECT_TRUE(Contains(msg, "expected a map with keys (robot)"));
}

}  // namespace
}  // namespace twin
