// The identification engine on synthetic tracker data: every error term's parameters recovered
// exactly from noise-free data and within the reported 3 sigma from noisy data, a term the data
// cannot see reported unidentifiable by name, fixed parameters held, and the geometric model
// identified together with terms and the tracker pose.
#include "calib/identification/engine.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "calib/measurements/tracker_set.h"
#include "test_models.h"
#include "tracker_synthetic.h"

namespace twin {
namespace {

using testing::Perturbed;
using testing::ReinovoLikeModel;
using testing::SyntheticTrackerPoints;

struct TermCase {
  TermSpec spec;
  std::vector<double> truth;  // realistic magnitudes
};

std::vector<TermCase> Cases() {
  return {{{"joint_compliance", 1, {}}, {2e-5}},
          {{"joint_compliance", 2, {}}, {3e-5}},
          {{"transmission_error", 3, {1}}, {1.5e-4, -1e-4}},
          {{"transmission_error", 5, {2}}, {-8e-5, 1.2e-4}},
          {{"backlash", 2, {}}, {-6e-5}},
          {{"thermal_growth", -1, {}}, {1.2e-5}},
          {{"thermal_drift", -1, {}}, {2e-9}},
          {{"mount_deflection", -1, {}}, {5e-5, -3e-5, 8e-5}}};
}

// Nominal chain, the truth, and the estimator's start (nominal plus the same term at zero).
// The truth is the start plus geometry errors (+-1 mm, +-0.002 rad) and the term's values,
// with the part the data cannot see removed (projected onto the identifiable directions of the
// start for these configurations): that part has no effect on the points to first order and
// the engine holds it, so only the visible part can be recovered.
struct TermSetup {
  KinematicModel nominal;
  RobotModel truth, start;
};

TermSetup MakeSetup(const TermCase& c, std::uint64_t seed, int points, std::uint64_t data_seed,
                    double sigma) {
  std::mt19937_64 rng(seed);
  TermSetup s;
  s.nominal = ReinovoLikeModel();
  s.start = WithTerm(MakeRobotModel(s.nominal), MakeErrorTerm(c.spec, s.nominal, "r1"));
  const Eigen::VectorXd phi0 = GetParameters(s.start);
  Eigen::VectorXd d = Eigen::VectorXd::Zero(phi0.size());
  const KinematicModel perturbed = Perturbed(s.nominal, rng, 0.001, 0.002);
  d.head(s.nominal.num_parameters()) = GetParameters(perturbed) - GetParameters(s.nominal);
  for (size_t k = 0; k < c.truth.size(); ++k) d(s.nominal.num_parameters() + k) = c.truth[k];
  TrackerSet probe(SyntheticTrackerPoints(s.start, points, data_seed, sigma));
  const ObservabilityReport rep = AnalyseIdentifiability(s.start, {&probe});
  Eigen::VectorXd x = d.cwiseQuotient(rep.column_scale);
  x -= rep.null_basis * (rep.null_basis.transpose() * x);
  s.truth = WithParameters(s.start, phi0 + x.cwiseProduct(rep.column_scale));
  return s;
}

TEST(Engine, EveryTermIsRecoveredExactlyFromNoiseFreeTrackerPoints) {
  for (const TermCase& c : Cases()) {
    const TermSetup s = MakeSetup(c, 41, 150, 42, 0.0);
    TrackerSet set(SyntheticTrackerPoints(s.truth, 150, 42));
    const IdentificationResult r = Identify(s.start, {&set});
    ASSERT_NE(r.status, IdentificationStatus::kFailed) << TermLabel(c.spec) << ": " << r.reason;
    const Eigen::VectorXd truth = GetParameters(s.truth);
    for (int i = 0; i < truth.size(); ++i) {
      // 1e-6 of the term's own magnitude (the target) for term parameters; geometry to
      // 1e-9 m or rad: noise-free data, solver tolerances of 1e-14.
      const bool term = i >= s.nominal.num_parameters();
      const double tol = term ? 1e-6 * std::abs(c.truth[i - s.nominal.num_parameters()]) : 1e-9;
      EXPECT_NEAR(GetParameters(r.model)(i), truth(i), tol)
          << TermLabel(c.spec) << ": " << r.parameters[i].name;
    }
    EXPECT_LT(r.sets[0].rms_after, 1e-10) << TermLabel(c.spec);
  }
}

TEST(Engine, NoisyTermsLieWithinThreeReportedSigmas) {
  constexpr double kSigma = 1e-5;  // 0.01 mm per axis, a good laser tracker
  for (const TermCase& c : Cases()) {
    const TermSetup s = MakeSetup(c, 43, 200, 44, kSigma);
    TrackerSet set(SyntheticTrackerPoints(s.truth, 200, 44, kSigma));
    const IdentificationResult r = Identify(s.start, {&set});
    ASSERT_NE(r.status, IdentificationStatus::kFailed) << r.reason;
    const Eigen::VectorXd truth = GetParameters(s.truth);
    const int g = s.nominal.num_parameters();
    for (int i = g; i < truth.size(); ++i) {
      const IdentifiedParameter& p = r.parameters[i];
      ASSERT_GT(p.sigma, 0.0) << p.name;
      // 3 sigma: a 0.3 % chance per parameter if the reported uncertainty is honest (seeded).
      EXPECT_LT(std::abs(p.estimated - truth(i)), 3.0 * p.sigma)
          << p.name << " estimated " << p.estimated << " true " << truth(i) << " sigma "
          << p.sigma;
      // The sigma is a real uncertainty, not a vanishing one: the noise moves the estimate.
      EXPECT_GT(p.sigma, 1e-4 * std::abs(c.truth[i - g])) << p.name;
    }
    // sigma0 is the residual against the stated noise: about 1 when the noise is as stated
    // (0.85..1.15: 600 rows give its relative standard error 1/sqrt(2 * 600) = 3 %).
    EXPECT_NEAR(r.sigma0, 1.0, 0.15) << TermLabel(c.spec);
  }
}

TEST(Engine, AnIsotropicMountDeflectionIsATrackerOffsetAndUnidentifiable) {
  // D = d I moves the point by d g_B whatever the pose: the tracker's position absorbs it.
  const TermSetup s = MakeSetup({{"mount_deflection", -1, {}}, {5e-5, 5e-5, 5e-5}}, 55, 100, 56,
                                0.0);
  TrackerSet set(SyntheticTrackerPoints(s.truth, 100, 56));
  const IdentificationResult r = Identify(s.start, {&set});
  const auto& u = r.observability.unidentifiable;
  bool named = false;
  for (const std::string& n : u) {
    named = named || (n.find("0.577 r1.mount.deflection_x") != std::string::npos &&
                      n.find("r1.mount.deflection_z") != std::string::npos);
  }
  EXPECT_TRUE(named) << ::testing::PrintToString(u);
}

TEST(Engine, ComplianceOfTheVerticalFirstJointIsUnidentifiableByName) {
  TermCase c{{"joint_compliance", 0, {}}, {0.0}};
  const TermSetup s = MakeSetup(c, 45, 100, 46, 0.0);
  TrackerSet set(SyntheticTrackerPoints(s.truth, 100, 46));
  const IdentificationResult r = Identify(s.start, {&set});
  const auto& u = r.observability.unidentifiable;
  EXPECT_NE(std::find(u.begin(), u.end(), "r1.joint1.compliance"), u.end())
      << "unidentifiable: " << ::testing::PrintToString(u);
  // Beside it, the rigid-motion gauge of the base (the tracker pose absorbs it) and the tool
  // link's rotation (a point has none).
  EXPECT_NE(std::find(u.begin(), u.end(), "r1.link1.theta"), u.end());
  EXPECT_EQ(r.model.term_values(0), 0.0) << "an unidentifiable parameter keeps its value";
}

TEST(Engine, ConstantTemperatureLeavesThermalGrowthInsideTheScaleOfTheArm) {
  TermCase c{{"thermal_growth", -1, {}}, {1.2e-5}};
  const TermSetup s = MakeSetup(c, 47, 100, 48, 0.0);
  std::vector<TrackerPoint> points = SyntheticTrackerPoints(s.truth, 100, 48);
  for (TrackerPoint& p : points) p.context.temperature_delta_K = 10.0;
  TrackerSet set(points);
  const IdentificationResult r = Identify(s.start, {&set});
  bool named = false;
  for (const std::string& u : r.observability.unidentifiable) {
    named = named || u.find("r1.thermal.per_kelvin") != std::string::npos;
  }
  EXPECT_TRUE(named) << ::testing::PrintToString(r.observability.unidentifiable);
}

// The disguise measure of model discovery: how far a term's columns can be told from the
// geometry's. A growth with the temperature barely varying is a scale of the arm in all but
// 1e-3 of it; with the temperature spread over 20 K it is far from any geometric correction.
TEST(Engine, TermGeometryDependenceSeesAGrowthAtNearlyOneTemperatureAsTheScale) {
  TermCase c{{"thermal_growth", -1, {}}, {1.2e-5}};
  const TermSetup s = MakeSetup(c, 57, 100, 58, 0.0);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> jitter(0.0, 0.01);
  std::vector<TrackerPoint> points = SyntheticTrackerPoints(s.truth, 100, 58, 1e-5);
  for (TrackerPoint& p : points) p.context.temperature_delta_K = 10.0 + jitter(rng);
  TrackerSet nearly(points);
  const IdentificationResult r = Identify(s.start, {&nearly});
  ASSERT_EQ(r.term_dependence.size(), 1u);
  const TermGeometryDependence& d = r.term_dependence[0];
  EXPECT_EQ(d.block, TermLabel(c.spec));
  ASSERT_EQ(d.canonical_correlations.size(), 1u);
  // 1 - cos is about (0.01 K / 10 K)^2 / 2 = 5e-7: 1e-5 leaves room for the other columns.
  EXPECT_GT(d.canonical_correlations[0], 1.0 - 1e-5);
  EXPECT_EQ(d.nearest_geometric.size(), 1u);
  EXPECT_EQ(d.nearest_geometric[0].rfind("r1.link", 0), 0u) << d.nearest_geometric[0];

  // SyntheticTrackerPoints' own temperatures: uniform over -5..15 K. The growth's column is
  // T_i times the scale's; its correlation with the scale's alone is mean / RMS of T = 0.65,
  // and no geometric correction follows a random temperature: below 0.9.
  TrackerSet spread(SyntheticTrackerPoints(s.truth, 100, 58, 1e-5));
  const IdentificationResult r2 = Identify(s.start, {&spread});
  ASSERT_EQ(r2.term_dependence.size(), 1u);
  EXPECT_LT(r2.term_dependence[0].canonical_correlations.at(0), 0.9);
  // A model without terms has none.
  TrackerSet plain(SyntheticTrackerPoints(s.truth, 100, 58, 1e-5));
  EXPECT_TRUE(Identify(MakeRobotModel(s.nominal), {&plain}).term_dependence.empty());
}

// A term that acts scales or bends the geometry's columns a little: a thermal growth of 2.3e-5
// /K over temperatures spread by 20 K scales the joint links by up to 4.6e-4 from one reading to
// the next, and that alone separates combinations the geometry cannot see (a joint link's length
// from the tool's, the base's rigid motion from the tracker's) by about 1e-4 of their columns,
// above the rank cut of 1e-6. The engine holds them as at the term's zero: the rank and the named
// combinations are those of the term at zero, and the term's own parameter stays identifiable.
TEST(Engine, AnActingTermDoesNotMakeTheGeometrysUnidentifiableCombinationsIdentifiable) {
  TermCase c{{"thermal_growth", -1, {}}, {2.3e-5}};
  const TermSetup s = MakeSetup(c, 59, 120, 60, 0.0);
  TrackerSet at_zero(SyntheticTrackerPoints(s.truth, 120, 60));
  const ObservabilityReport zero = AnalyseIdentifiability(s.start, {&at_zero});
  RobotModel acting = s.start;
  acting.term_values(0) = c.truth[0];
  TrackerSet at_value(SyntheticTrackerPoints(s.truth, 120, 60));
  const ObservabilityReport value = AnalyseIdentifiability(acting, {&at_value});
  EXPECT_EQ(value.rank, zero.rank);
  EXPECT_EQ(value.unidentifiable.size(), zero.unidentifiable.size())
      << ::testing::PrintToString(value.unidentifiable);
  for (const std::string& u : value.unidentifiable) {
    EXPECT_EQ(u.find("thermal"), std::string::npos) << u;
  }
  // The identification from the acting start holds them too (its rank is the analysis'), and
  // recovers the noise-free truth from there (tolerances of the exact-recovery test above).
  TrackerSet set(SyntheticTrackerPoints(s.truth, 120, 60));
  const IdentificationResult r = Identify(acting, {&set});
  ASSERT_NE(r.status, IdentificationStatus::kFailed) << r.reason;
  EXPECT_EQ(r.observability.rank, zero.rank);
  EXPECT_NEAR(r.model.term_values(0), s.truth.term_values(0), 1e-6 * c.truth[0]);
  EXPECT_LT(r.sets[0].rms_after, 1e-10);
}

TEST(Engine, FixedParametersAreHeldAndOthersStillFit) {
  TermCase c{{"joint_compliance", 1, {}}, {2e-5}};
  const TermSetup s = MakeSetup(c, 49, 120, 50, 0.0);
  TrackerSet set(SyntheticTrackerPoints(s.truth, 120, 50));
  IdentificationOptions o;
  o.fixed = {"joint_compliance (joint 2)", "r1.link7.alpha"};
  const IdentificationResult r = Identify(s.start, {&set}, o);
  EXPECT_EQ(r.model.term_values(0), 0.0);
  EXPECT_TRUE(r.parameters[35].fixed);
  EXPECT_EQ(r.parameters[35].sigma, 0.0);
  // Without the compliance, the residual stays (the geometry cannot explain the sag) but the
  // fit still lowers it.
  EXPECT_LT(r.sets[0].rms_after, r.sets[0].rms_before);
  EXPECT_GT(r.sets[0].rms_after, 1e-6);
  // The fixed names are built by our procedures from the layout: an unknown one is our bug.
  o.fixed = {"r1.joint9.compliance"};
  EXPECT_THROW(Identify(s.start, {&set}, o), PreconditionError);
}

TEST(Engine, SetsThatDoNotFitTheModelAreRefusedWithTheRow) {
  TermCase c{{"thermal_growth", -1, {}}, {1.2e-5}};
  const TermSetup s = MakeSetup(c, 51, 20, 52, 0.0);
  std::vector<TrackerPoint> points = SyntheticTrackerPoints(s.truth, 20, 52);
  points[7].context.temperature_delta_K = std::nan("");
  TrackerSetOptions so;
  so.source = "cell.csv";
  TrackerSet set(points, so);
  try {
    Identify(s.start, {&set});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cell.csv:9"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("needs a temperature change"), std::string::npos);
  }
  // No set at all, or a null one, is a caller's bug, not the data's.
  EXPECT_THROW(Identify(s.start, {}), PreconditionError);
  EXPECT_THROW(Identify(s.start, {nullptr}), PreconditionError);
}

TEST(Engine, CorrelationsAreReportedStrongestFirstWithinTheThreshold) {
  TermCase c{{"joint_compliance", 1, {}}, {2e-5}};
  const TermSetup s = MakeSetup(c, 53, 150, 54, 1e-5);
  TrackerSet set(SyntheticTrackerPoints(s.truth, 150, 54, 1e-5));
  IdentificationOptions o;
  o.correlation_threshold = 0.5;
  const IdentificationResult r = Identify(s.start, {&set}, o);
  for (size_t i = 0; i < r.correlations.size(); ++i) {
    EXPECT_GE(std::abs(r.correlations[i].rho), 0.5);
    EXPECT_LE(std::abs(r.correlations[i].rho), 1.0 + 1e-9);
    if (i > 0) {
      EXPECT_LE(std::abs(r.correlations[i].rho), std::abs(r.correlations[i - 1].rho));
    }
  }
}

}  // namespace
}  // namespace twin
