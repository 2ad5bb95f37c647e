#include "calib/diagnosis/session_scoring.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "calib/common/errors.h"
#include "calib/diagnosis/comparators.h"
#include "calib/diagnosis/discovery_result.h"

namespace twin {

void ValidateSessionScoringOptions(const SessionScoringOptions& o, const std::string& where) {
  if (o.halvings < 1 || o.halvings > 1000) {
    throw InputError(where + ".halvings",
                     "must be from 1 to 1000, got " + std::to_string(o.halvings));
  }
}

std::vector<SessionHalving> SessionHalvings(const std::vector<TrackerPoint>& session,
                                            const SessionScoringOptions& o,
                                            const std::string& source) {
  TWIN_REQUIRE(o.halvings >= 1, "SessionHalvings: " + std::to_string(o.halvings) + " halvings");
  const std::vector<int> pose_of = PoseGroups(session);
  const int poses = session.empty() ? 0 : *std::max_element(pose_of.begin(), pose_of.end()) + 1;
  if (poses < 6) {
    throw InputError(source, "second-session scoring: " + std::to_string(poses) +
                                 " different poses; a halving needs 3 to fit the tracker pose "
                                 "on and 3 to score (6 or more)");
  }
  std::vector<std::vector<int>> members(poses);
  for (std::size_t i = 0; i < session.size(); ++i) {
    members[pose_of[i]].push_back(static_cast<int>(i));
  }
  std::mt19937_64 rng(o.seed);
  std::vector<int> order(poses);
  std::vector<SessionHalving> out;
  for (int h = 0; h < o.halvings; ++h) {
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), rng);
    SessionHalving half;
    for (int k = 0; k < poses; ++k) {
      std::vector<int>& part = k < poses / 2 ? half.fit : half.scored;
      part.insert(part.end(), members[order[k]].begin(), members[order[k]].end());
    }
    out.push_back(std::move(half));
  }
  return out;
}

SessionScore ScorePredictionsOnSession(const std::vector<Vector3>& p_B,
                                       const std::vector<TrackerPoint>& session,
                                       const std::vector<SessionHalving>& halvings,
                                       const std::string& source) {
  TWIN_REQUIRE(p_B.size() == session.size() && !halvings.empty(),
               "ScorePredictionsOnSession: " + std::to_string(p_B.size()) + " predictions for " +
                   std::to_string(session.size()) + " points, " +
                   std::to_string(halvings.size()) + " halvings");
  SessionScore s;
  s.points = static_cast<int>(session.size());
  s.halvings = static_cast<int>(halvings.size());
  for (const SessionHalving& half : halvings) {
    std::vector<Vector3> a, b;
    for (int i : half.fit) {
      a.push_back(p_B[i]);
      b.push_back(session[i].p_T);
    }
    Transform X_TB = Transform::Identity();
    if (!FitRigid(a, b, &X_TB)) {
      throw InputError(source, "second-session scoring: the points a halving fits the tracker "
                               "pose on are collinear");
    }
    double sum = 0;
    for (int i : half.scored) sum += (X_TB * p_B[i] - session[i].p_T).squaredNorm();
    s.rms_per_halving_m.push_back(std::sqrt(sum / half.scored.size()));
  }
  const std::vector<double>& r = s.rms_per_halving_m;
  s.rms_m = std::accumulate(r.begin(), r.end(), 0.0) / r.size();
  double ss = 0;
  for (double v : r) ss += (v - s.rms_m) * (v - s.rms_m);
  s.rms_sd_m = r.size() > 1 ? std::sqrt(ss / (r.size() - 1)) : 0.0;
  s.rms_min_m = *std::min_element(r.begin(), r.end());
  s.rms_max_m = *std::max_element(r.begin(), r.end());
  return s;
}

SessionScore ScoreModelOnSession(const RobotModel& model, const std::vector<TrackerPoint>& session,
                                 const std::vector<SessionHalving>& halvings,
                                 const std::string& source) {
  std::vector<Vector3> p_B;
  p_B.reserve(session.size());
  for (const TrackerPoint& p : session) p_B.push_back(EndPose(model, p.context).translation());
  return ScorePredictionsOnSession(p_B, session, halvings, source);
}

int WorseHalvings(const SessionScore& after, const SessionScore& before) {
  TWIN_REQUIRE(after.rms_per_halving_m.size() == before.rms_per_halving_m.size(),
               "WorseHalvings: scores over different halvings");
  int worse = 0;
  for (std::size_t h = 0; h < after.rms_per_halving_m.size(); ++h) {
    worse += after.rms_per_halving_m[h] > before.rms_per_halving_m[h] ? 1 : 0;
  }
  return worse;
}

namespace discovery {
namespace {

// "a -> b mm": a step's session RMS change for a warning.
std::string SessionChange(const SessionScore& before, const SessionScore& after) {
  return Mm(before.rms_m) + " -> " + Mm(after.rms_m);
}

}  // namespace

void ScoreOnSecondSession(const TrackerData& data, const RobotModel& start,
                          const DiscoveryOptions& o, DiscoveryResult* out) {
  DiscoveryResult& r = *out;
  const std::string source = o.set.source + " (second session)";
  const std::vector<SessionHalving> halvings =
      SessionHalvings(o.session, o.session_scoring, source);
  const auto score = [&](const RobotModel& model, const std::string& what) {
    const Fit fit = data.FitOn(model, {}, what + ", all data, for the second session");
    return ScoreModelOnSession(fit.result.model, o.session, halvings, source);
  };
  if (o.progress) o.progress("diagnosis: scoring the models on the second session");
  SessionScore current = score(start, "starting model");
  r.session_start = current;
  for (DiscoveryStep& s : r.steps) {
    if (s.accepted < 0) {
      s.session = current;  // nothing added: the base's score
      continue;
    }
    const std::string& label = s.candidates[s.accepted].label;
    const SessionScore after = score(s.model_after, "step " + std::to_string(s.index) + " model");
    s.session = after;
    s.session_worse = after.rms_m > current.rms_m;
    s.session_worse_halvings = WorseHalvings(after, current);
    if (s.session_worse) {
      r.warnings.push_back("second session: step " + std::to_string(s.index) + "'s term " +
                           label + " makes it WORSE than the model before it (RMS " +
                           SessionChange(current, after) + ", mean over " +
                           std::to_string(after.halvings) + " halvings; worse on " +
                           std::to_string(s.session_worse_halvings) + ")");
    }
    current = after;
  }
  r.session_discovered = current;
}

}  // namespace discovery
}  // namespace twin
