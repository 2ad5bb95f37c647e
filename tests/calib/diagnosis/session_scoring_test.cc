#include "calib/diagnosis/session_scoring.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "calib/diagnosis/model_discovery.h"
#include "test_models.h"
#include "tracker_synthetic.h"

namespace twin {
namespace {

using testing::ReinovoLikeModel;
using testing::SyntheticTrackerPoints;

// A tracker pose for hand-built cases: 30 deg about (1, 2, 3), moved (0.5, -1, 2) m.
Transform HandPose() {
  Transform X = Transform::Identity();
  X.linear() = Eigen::AngleAxisd(DegToRad(30.0), Vector3(1, 2, 3).normalized()).toRotationMatrix();
  X.translation() = Vector3(0.5, -1.0, 2.0);
  return X;
}

// Session points at p_T = X p_B + d (d: an error the fit half does not carry).
std::vector<TrackerPoint> Measured(const std::vector<Vector3>& p_B, const std::vector<Vector3>& d) {
  std::vector<TrackerPoint> out(p_B.size());
  for (std::size_t i = 0; i < p_B.size(); ++i) {
    out[i].row = static_cast<int>(i) + 2;
    out[i].context.q = JointVector::Constant(1, 0.1 * i);  // distinct poses
    out[i].p_T = HandPose() * p_B[i] + d[i];
  }
  return out;
}

// Six hand-built points and two hand-made halvings: the fit halves are exact (the pose is
// recovered exactly), the scored points carry known offsets, so each halving's RMS is the RMS
// of those offsets and the score their mean and standard deviation.
TEST(SessionScoring, TheScoreOfATinyHandBuiltCaseIsItsOwnArithmetic) {
  const std::vector<Vector3> p_B = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}, {0, 1, 1}};
  const std::vector<Vector3> d = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0.003, 0, 0},
                                  {0, 0.004, 0}, {0, 0, 0.001}};
  const std::vector<TrackerPoint> session = Measured(p_B, d);
  // Both fit halves hold only points without offset (the second halving leaves point 3 out).
  const std::vector<SessionHalving> exact = {{{0, 1, 2}, {3, 4, 5}}, {{0, 1, 2}, {4, 5}}};
  const SessionScore s = ScorePredictionsOnSession(p_B, session, exact, "hand");
  const double h1 = std::sqrt((9e-6 + 16e-6 + 1e-6) / 3.0), h2 = std::sqrt((16e-6 + 1e-6) / 2.0);
  ASSERT_EQ(s.rms_per_halving_m.size(), 2u);
  // The pose is fitted on 3 exact points: recovered to rounding (1e-12 m is far below the
  // offsets' micrometres and far above double rounding of metre-sized coordinates).
  EXPECT_NEAR(s.rms_per_halving_m[0], h1, 1e-12);
  EXPECT_NEAR(s.rms_per_halving_m[1], h2, 1e-12);
  EXPECT_NEAR(s.rms_m, (h1 + h2) / 2.0, 1e-12);
  EXPECT_NEAR(s.rms_sd_m, std::abs(h1 - h2) / std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(s.rms_min_m, std::min(h1, h2), 1e-12);
  EXPECT_NEAR(s.rms_max_m, std::max(h1, h2), 1e-12);
  EXPECT_EQ(s.points, 6);
  EXPECT_EQ(s.halvings, 2);
  // A fit half with an offset point tilts the pose: the score is no longer the offsets' RMS
  // (the pose is refitted on the fit half, not taken from anywhere else).
  const std::vector<SessionHalving> tilting = {{{0, 1, 2}, {3, 4, 5}}, {{0, 1, 2, 3}, {4, 5}}};
  const SessionScore tilted = ScorePredictionsOnSession(p_B, session, tilting, "hand");
  EXPECT_GT(std::abs(tilted.rms_per_halving_m[1] - h2), 1e-6);
}

// A model's score on a synthetic session against the test's own computation: Eigen's
// Umeyama fit (no scale) of the fit half, the RMS over the scored half, averaged.
TEST(SessionScoring, AModelsScoreIsTheMeanOverHalvingsOfThePoseRefittedOnTheOtherHalf) {
  const RobotModel truth = MakeRobotModel(ReinovoLikeModel(0));
  std::mt19937_64 rng(5);
  const RobotModel model = MakeRobotModel(testing::Perturbed(ReinovoLikeModel(0), rng, 1e-3, 1e-3));
  const std::vector<TrackerPoint> session = SyntheticTrackerPoints(truth, 40, 9, 1e-5);
  SessionScoringOptions o;
  o.halvings = 5;
  const std::vector<SessionHalving> halvings = SessionHalvings(session, o, "synthetic");
  const SessionScore s = ScoreModelOnSession(model, session, halvings, "synthetic");
  double mean = 0;
  for (std::size_t h = 0; h < halvings.size(); ++h) {
    Eigen::Matrix3Xd a(3, halvings[h].fit.size()), b(3, halvings[h].fit.size());
    for (std::size_t k = 0; k < halvings[h].fit.size(); ++k) {
      const TrackerPoint& p = session[halvings[h].fit[k]];
      a.col(k) = EndPose(model, p.context).translation();
      b.col(k) = p.p_T;
    }
    const Eigen::Matrix4d X = Eigen::umeyama(a, b, false);
    double sum = 0;
    for (int i : halvings[h].scored) {
      const Vector3 p_B = EndPose(model, session[i].context).translation();
      const Vector3 p = X.topLeftCorner<3, 3>() * p_B + X.topRightCorner<3, 1>();
      sum += (p - session[i].p_T).squaredNorm();
    }
    const double rms = std::sqrt(sum / halvings[h].scored.size());
    // Two least-squares solvers of the same problem: they agree to rounding of the 1 mm
    // errors (1e-10 m, a 1e-7 relative difference, far above double precision).
    EXPECT_NEAR(s.rms_per_halving_m[h], rms, 1e-10) << "halving " << h;
    mean += rms / halvings.size();
  }
  EXPECT_NEAR(s.rms_m, mean, 1e-10);
  // The perturbed geometry leaves ~mm errors: the score is not the noise (a sanity floor).
  EXPECT_GT(s.rms_m, 1e-4);
}

TEST(SessionScoring, HalvingsSplitWholePosesInTwoSeededTheSameForEveryCall) {
  std::vector<TrackerPoint> session = SyntheticTrackerPoints(MakeRobotModel(ReinovoLikeModel(0)),
                                                             11, 3);
  session.push_back(session[4]);  // a repeat of pose 5
  SessionScoringOptions o;
  o.halvings = 20;
  const auto halvings = SessionHalvings(session, o, "s");
  ASSERT_EQ(halvings.size(), 20u);
  std::set<std::vector<int>> distinct;
  for (const SessionHalving& h : halvings) {
    std::vector<int> all = h.fit;
    all.insert(all.end(), h.scored.begin(), h.scored.end());
    std::sort(all.begin(), all.end());
    ASSERT_EQ(all.size(), 12u);
    for (int i = 0; i < 12; ++i) EXPECT_EQ(all[i], i);
    // 11 poses: 5 fit, 6 scored; the repeat goes with its pose.
    const bool fit4 = std::count(h.fit.begin(), h.fit.end(), 4) > 0;
    EXPECT_EQ(fit4, std::count(h.fit.begin(), h.fit.end(), 11) > 0);
    EXPECT_EQ(h.fit.size(), fit4 ? 6u : 5u);
    distinct.insert(h.fit);
  }
  EXPECT_GT(distinct.size(), 10u);  // 462 ways to choose 5 of 11 poses: random halvings differ
  const auto again = SessionHalvings(session, o, "s");
  for (std::size_t h = 0; h < halvings.size(); ++h) EXPECT_EQ(again[h].fit, halvings[h].fit);
}

TEST(SessionScoring, FewerThanSixPosesOrBadHalvingsAreBadInput) {
  const auto session = SyntheticTrackerPoints(MakeRobotModel(ReinovoLikeModel(0)), 5, 3);
  try {
    SessionHalvings(session, {}, "second.csv");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("second.csv"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("5 different poses"), std::string::npos) << e.what();
  }
  SessionScoringOptions o;
  o.halvings = 0;
  EXPECT_THROW(ValidateSessionScoringOptions(o, "diagnosis.session_scoring"), InputError);
}

TEST(SessionScoring, WorseHalvingsCountsPairedHalvings) {
  SessionScore a, b;
  a.rms_per_halving_m = {1, 2, 3};
  b.rms_per_halving_m = {2, 1, 3};
  EXPECT_EQ(WorseHalvings(a, b), 1);
  EXPECT_EQ(WorseHalvings(b, a), 1);
}

// The diagnosis's second session (DiscoveryOptions::session). The first session's arm has a
// compliance at joint 2 (3e-5 rad/(N m): ~0.5 mm of sag at the tool, far above the 10 um
// noise), which discovery adds. A second session of the same arm confirms it; a second
// session without it (the same geometry, the load that bent it gone) is made worse by it: the
// step is flagged and warned of by name.
struct SessionCase {
  RobotModel nominal, stiff, soft;
};

SessionCase MakeSessionCase() {
  std::mt19937_64 rng(12);
  const KinematicModel nominal = ReinovoLikeModel(1);
  KinematicModel chain = testing::Perturbed(nominal, rng, 1e-3, DegToRad(0.1));
  chain.X_BL0 = nominal.X_BL0;
  chain.X_LtE = nominal.X_LtE;
  SessionCase c{MakeRobotModel(nominal), MakeRobotModel(chain), {}};
  c.soft = WithTerm(c.stiff, MakeErrorTerm({"joint_compliance", 1, {}}, chain, chain.name));
  c.soft.term_values(c.soft.term_values.size() - 1) = 3e-5;
  return c;
}

DiscoveryResult DiscoverWithSession(const SessionCase& c, const RobotModel& second) {
  DiscoveryOptions o;
  o.candidates = {{"joint_compliance", 1, {}}};
  o.set.default_sigma = 1e-5;
  o.set.source = "first.csv";
  o.black_box = false;  // its own tests (black_box_test.cc)
  // The second session: another tracker pose, other configurations.
  Transform X = testing::TrackerPose();
  X.translation() += Vector3(0.3, -0.2, 0.1);
  o.session = SyntheticTrackerPoints(second, 80, 21, 1e-5, X);
  return DiscoverTrackerModel(c.nominal, SyntheticTrackerPoints(c.soft, 150, 4, 1e-5), o);
}

TEST(SessionScoring, ATermThatMakesTheSecondSessionWorseIsFlaggedAndNamed) {
  const SessionCase c = MakeSessionCase();
  const DiscoveryResult r = DiscoverWithSession(c, c.stiff);
  ASSERT_EQ(r.verdict, DiscoveryVerdict::kEffectsAdded) << r.reason;
  ASSERT_TRUE(r.session_start && r.session_discovered);
  ASSERT_TRUE(r.steps[0].session);
  EXPECT_TRUE(r.steps[0].session_worse);
  EXPECT_GT(r.steps[0].session->rms_m, r.session_start->rms_m);
  EXPECT_GT(r.steps[0].session_worse_halvings, 0);
  EXPECT_EQ(r.session_discovered->rms_m, r.steps.back().session->rms_m);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("joint_compliance (joint 2)"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[0].find("WORSE"), std::string::npos) << r.warnings[0];
}

TEST(SessionScoring, ATermTheSecondSessionConfirmsIsNotFlagged) {
  const SessionCase c = MakeSessionCase();
  const DiscoveryResult r = DiscoverWithSession(c, c.soft);
  ASSERT_EQ(r.verdict, DiscoveryVerdict::kEffectsAdded) << r.reason;
  ASSERT_TRUE(r.steps[0].session);
  EXPECT_FALSE(r.steps[0].session_worse);
  EXPECT_LT(r.session_discovered->rms_m, r.session_start->rms_m);
  EXPECT_TRUE(r.warnings.empty());
  // The discovered model on a session of the same arm: the tracker's noise, sqrt(3) sigma a
  // point, plus the estimation error; 2x that bounds it (the sag left ~0.5 mm).
  EXPECT_LT(r.session_discovered->rms_m, 2.0 * std::sqrt(3.0) * 1e-5);
}

TEST(SessionScoring, WithoutASecondSessionNothingIsScored) {
  const SessionCase c = MakeSessionCase();
  DiscoveryOptions o;
  o.candidates = {{"joint_compliance", 1, {}}};
  o.set.default_sigma = 1e-5;
  o.black_box = false;
  const DiscoveryResult r =
      DiscoverTrackerModel(c.nominal, SyntheticTrackerPoints(c.soft, 150, 4, 1e-5), o);
  EXPECT_FALSE(r.session_start);
  EXPECT_FALSE(r.session_discovered);
  for (const DiscoveryStep& s : r.steps) EXPECT_FALSE(s.session);
  EXPECT_TRUE(r.warnings.empty());
}

}  // namespace
}  // namespace twin
