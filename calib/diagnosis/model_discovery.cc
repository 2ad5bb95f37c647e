#include "calib/diagnosis/model_discovery.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <numeric>
#include <random>
#include <sstream>
#include <thread>

#include "calib/common/errors.h"
#include "calib/diagnosis/statistics.h"

namespace twin {
namespace {

// Held-out residuals of one cross-validation: e[i] = predicted - measured for point i, from
// the model trained without i's fold.
struct CrossValidation {
  std::vector<Vector3> e;
  double unknowns = 0;  // mean over folds of the fit's unknowns
  double train_coordinates = 0;  // mean over folds of 3 n_train
  double Sse() const {
    double s = 0;
    for (const Vector3& v : e) s += v.squaredNorm();
    return s;
  }
  double Rms() const { return e.empty() ? 0.0 : std::sqrt(Sse() / e.size()); }
};

struct Fit {
  IdentificationResult result;
  Transform X_TB = Transform::Identity();
};

Fit FitModel(const RobotModel& model, const std::vector<TrackerPoint>& points,
             const DiscoveryOptions& o, const std::string& what) {
  TrackerSetOptions so = o.set;
  so.source = o.set.source + " (" + what + ")";
  TrackerSet set(points, so);
  Fit f;
  f.result = Identify(model, {&set}, o.engine);
  if (f.result.status == IdentificationStatus::kFailed) {
    throw InputError(so.source, "the identification failed: " + f.result.reason);
  }
  f.X_TB = set.X_TB();
  return f;
}

CrossValidation CrossValidate(const RobotModel& model, const std::vector<TrackerPoint>& points,
                              const std::vector<int>& fold_of, int folds,
                              const DiscoveryOptions& o, const std::string& what) {
  CrossValidation cv;
  cv.e.assign(points.size(), Vector3::Zero());
  for (int k = 0; k < folds; ++k) {
    std::vector<TrackerPoint> train;
    std::vector<int> test;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (fold_of[i] == k) {
        test.push_back(static_cast<int>(i));
      } else {
        train.push_back(points[i]);
      }
    }
    if (test.empty()) continue;
    const Fit fit = FitModel(model, train, o, what + ", fold " + std::to_string(k + 1));
    for (int i : test) {
      cv.e[i] = fit.X_TB * EndPose(fit.result.model, points[i].context).translation() -
                points[i].p_T;
    }
    cv.unknowns += fit.result.unknowns / static_cast<double>(folds);
    cv.train_coordinates += 3.0 * train.size() / folds;
  }
  return cv;
}

double SigmaOf(const TrackerPoint& p, const DiscoveryOptions& o) {
  return p.sigma > 0.0 ? p.sigma : o.set.default_sigma;
}

// Workspace blocks: k-means (Lloyd) on the measured points, started from the point nearest
// the centroid and then each time the point farthest from the centres so far (deterministic).
std::vector<int> RegionFolds(const std::vector<TrackerPoint>& points, int k, std::string* rule) {
  const int n = static_cast<int>(points.size());
  Vector3 mean = Vector3::Zero();
  for (const TrackerPoint& p : points) mean += p.p_T;
  mean /= n;
  std::vector<Vector3> centres;
  int first = 0;
  for (int i = 1; i < n; ++i) {
    if ((points[i].p_T - mean).norm() < (points[first].p_T - mean).norm()) first = i;
  }
  centres.push_back(points[first].p_T);
  while (static_cast<int>(centres.size()) < k) {
    int far = 0;
    double best = -1;
    for (int i = 0; i < n; ++i) {
      double d = std::numeric_limits<double>::infinity();
      for (const Vector3& c : centres) d = std::min(d, (points[i].p_T - c).squaredNorm());
      if (d > best) {
        best = d;
        far = i;
      }
    }
    centres.push_back(points[far].p_T);
  }
  std::vector<int> fold(n, 0);
  for (int it = 0; it < 100; ++it) {
    bool changed = false;
    for (int i = 0; i < n; ++i) {
      int nearest = 0;
      for (int c = 1; c < k; ++c) {
        if ((points[i].p_T - centres[c]).squaredNorm() <
            (points[i].p_T - centres[nearest]).squaredNorm()) {
          nearest = c;
        }
      }
      changed = changed || nearest != fold[i];
      fold[i] = nearest;
    }
    std::vector<Vector3> sum(k, Vector3::Zero());
    std::vector<int> count(k, 0);
    for (int i = 0; i < n; ++i) {
      sum[fold[i]] += points[i].p_T;
      ++count[fold[i]];
    }
    for (int c = 0; c < k; ++c) {
      if (count[c] > 0) centres[c] = sum[c] / count[c];
    }
    if (!changed && it > 0) break;
  }
  std::vector<int> count(k, 0);
  for (int f : fold) ++count[f];
  std::ostringstream os;
  os << k << " workspace blocks by k-means on the measured points (sizes";
  for (int c = 0; c < k; ++c) os << (c ? ", " : " ") << count[c];
  os << "); each block predicted by the model trained on the others";
  *rule = os.str();
  return fold;
}

std::vector<int> RandomFolds(int n, int k, std::uint64_t seed) {
  std::vector<int> index(n);
  std::iota(index.begin(), index.end(), 0);
  std::mt19937_64 rng(seed);
  std::shuffle(index.begin(), index.end(), rng);
  std::vector<int> fold(n);
  for (int r = 0; r < n; ++r) fold[index[r]] = r % k;
  return fold;
}

// Per point: sigma_i^2 I + sigma_q^2 J J^T (header), J by central differences of `model`.
std::vector<Matrix3> NoiseCovariances(const RobotModel& model,
                                      const std::vector<TrackerPoint>& points,
                                      const DiscoveryOptions& o) {
  std::vector<Matrix3> out;
  const double h = 1e-6;
  for (const TrackerPoint& p : points) {
    const double s = SigmaOf(p, o);
    Matrix3 S = s * s * Matrix3::Identity();
    if (o.joint_sigma_rad > 0.0) {
      for (int i = 0; i < p.context.q.size(); ++i) {
        MeasurementContext plus = p.context, minus = p.context;
        plus.q(i) += h;
        minus.q(i) -= h;
        const Vector3 j = (EndPose(model, plus).translation() - EndPose(model, minus).translation()) /
                          (2.0 * h);
        S += o.joint_sigma_rad * o.joint_sigma_rad * j * j.transpose();
      }
    }
    out.push_back(S);
  }
  return out;
}

NoiseFloor EstimateNoise(const std::vector<TrackerPoint>& points,
                         const std::vector<Matrix3>& covariance, const DiscoveryOptions& o) {
  NoiseFloor nf;
  double sum = 0, tracker = 0;
  int stated = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    sum += covariance[i].trace() / 3.0;
    tracker += SigmaOf(points[i], o) * SigmaOf(points[i], o);
    if (points[i].sigma > 0.0) ++stated;
  }
  nf.sigma_m = std::sqrt(sum / points.size());
  nf.tracker_sigma_m = std::sqrt(tracker / points.size());
  nf.joint_sigma_rad = o.joint_sigma_rad;
  nf.source = stated == static_cast<int>(points.size())
                  ? "the sigma stated for each point"
                  : (stated == 0 ? "the set's default sigma (no point states one)"
                                 : "the stated sigmas, the set's default where a point has none");
  if (o.joint_sigma_rad > 0.0) nf.source += ", with the stated joint reading noise through the model";
  // Repeated poses: the same joint readings to 1e-6 rad.
  std::vector<bool> used(points.size(), false);
  double ss = 0;
  int dof = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (used[i]) continue;
    std::vector<int> group{static_cast<int>(i)};
    for (std::size_t j = i + 1; j < points.size(); ++j) {
      if (!used[j] && points[j].context.q.size() == points[i].context.q.size() &&
          (points[j].context.q - points[i].context.q).cwiseAbs().maxCoeff() < 1e-6) {
        group.push_back(static_cast<int>(j));
        used[j] = true;
      }
    }
    if (group.size() < 2) continue;
    ++nf.repeated_groups;
    Vector3 m = Vector3::Zero();
    for (int g : group) m += points[g].p_T;
    m /= group.size();
    for (int g : group) ss += (points[g].p_T - m).squaredNorm();
    dof += 3 * (static_cast<int>(group.size()) - 1);
  }
  if (dof > 0) nf.repeat_sigma_m = std::sqrt(ss / dof);
  return nf;
}

ResidualTest TestResiduals(const CrossValidation& cv, const std::vector<TrackerPoint>& points,
                           const std::vector<Matrix3>& covariance, const DiscoveryOptions& o,
                           const std::string& held_out) {
  ResidualTest t;
  t.held_out = held_out;
  t.points = static_cast<int>(points.size());
  t.rms_m = cv.Rms();
  double chi2 = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    chi2 += cv.e[i].dot(covariance[i].ldlt().solve(cv.e[i]));
  }
  t.dof = 3.0 * points.size();
  t.inflation = cv.train_coordinates > 0 ? 1.0 + cv.unknowns / cv.train_coordinates : 1.0;
  t.statistic = chi2 / t.inflation;
  t.p_value = stats::ChiSquareUpperTail(t.statistic, t.dof);
  t.systematic = t.p_value < o.alpha;
  return t;
}

std::string Mm(double m) {
  std::ostringstream os;
  os.precision(4);
  os << 1e3 * m << " mm";
  return os.str();
}

// Scores one candidate against the step's base (its region cross-validation `base_cv`).
CandidateScore ScoreCandidate(const RobotModel& base, int base_rank, const TermSpec& spec,
                              const std::vector<TrackerPoint>& points,
                              const std::vector<int>& region, const CrossValidation& base_cv,
                              const DiscoveryOptions& o) {
  CandidateScore c;
  c.spec = spec;
  c.label = TermLabel(spec);
  RobotModel model;
  try {
    model = WithTerm(base, MakeErrorTerm(spec, base.chain, base.name(), "candidate " + c.label));
  } catch (const InputError& e) {
    c.applicable = false;
    c.note = e.what();
    return c;
  }
  for (const TrackerPoint& p : points) {
    const std::string missing = MissingContext(model, p.context);
    if (!missing.empty()) {
      c.applicable = false;
      c.note = "not applicable: " + missing + " (row " + std::to_string(p.row) + ")";
      return c;
    }
  }
  const int added = static_cast<int>(model.terms.back()->parameters().size());
  const Fit all = FitModel(model, points, o, "candidate " + c.label + ", every point");
  const int first = model.num_parameters() - added;
  for (int k = 0; k < added; ++k) {
    const IdentifiedParameter& ip = all.result.parameters[first + k];
    c.parameters.push_back({ip.name, ip.unit, ip.estimated, ip.sigma});
  }
  const int rank = all.result.observability.rank;
  if (rank <= base_rank) {
    c.identifiable = false;
    c.note = "unidentifiable from these points: the rank does not rise with its " +
             std::to_string(added) + " parameter(s) (the measurements cannot tell it from the "
             "geometry, or it has nothing to act on)";
    return c;
  }
  if (rank < base_rank + added) {
    // Partly identifiable (e.g. a mount deflection along the flange axis is the tool length's):
    // the engine identifies only the combinations the data sees, the rest stay at zero.
    c.note = "partly identifiable: the rank rises by " + std::to_string(rank - base_rank) +
             " of its " + std::to_string(added) + " parameters";
  }
  const Eigen::MatrixXd& C = all.result.covariance;
  const int geometric = model.chain.num_parameters();
  for (int k = 0; k < added; ++k) {
    const int a = first + k;
    for (int g = 0; g < geometric; ++g) {
      const double denom = std::sqrt(C(a, a) * C(g, g));
      if (!(denom > 0.0)) continue;
      const double rho = std::abs(C(a, g) / denom);
      if (rho > c.max_geometry_correlation) {
        c.max_geometry_correlation = rho;
        c.correlated_with = all.result.parameters[g].name;
      }
    }
  }
  const CrossValidation cv =
      CrossValidate(model, points, region, o.folds, o, "candidate " + c.label);
  c.heldout_rms_m = cv.Rms();
  const double base_sse = base_cv.Sse();
  c.gain_percent = base_sse > 0 ? 100.0 * (1.0 - cv.Sse() / base_sse) : 0.0;
  std::vector<double> d(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    d[i] = base_cv.e[i].squaredNorm() - cv.e[i].squaredNorm();
  }
  c.p_value = stats::WilcoxonSignedRankGreater(d).p_value;
  c.tested = true;
  return c;
}

// Quantities the residual is correlated with and mapped against, per point.
struct Quantity {
  std::string name, unit;
  std::vector<double> values;
};

std::vector<Quantity> Quantities(const RobotModel& model, const std::vector<TrackerPoint>& points) {
  std::vector<Quantity> out;
  const int n = model.chain.num_joints();
  for (int j = 0; j < n; ++j) {
    Quantity q{"q" + std::to_string(j + 1), "rad", {}};
    for (const TrackerPoint& p : points) q.values.push_back(p.context.q(j));
    out.push_back(q);
  }
  std::vector<Eigen::VectorXd> tau;
  for (const TrackerPoint& p : points) tau.push_back(GravityTorques(model, p.context.q));
  for (int j = 0; j < n; ++j) {
    Quantity q{"tau" + std::to_string(j + 1), "N m", {}};
    for (const Eigen::VectorXd& t : tau) q.values.push_back(t(j));
    out.push_back(q);
  }
  Quantity order{"order", "row", {}};
  for (const TrackerPoint& p : points) order.values.push_back(p.row);
  out.push_back(order);
  if (std::all_of(points.begin(), points.end(),
                  [](const TrackerPoint& p) { return p.context.has_time(); })) {
    Quantity q{"time", "s", {}};
    for (const TrackerPoint& p : points) q.values.push_back(p.context.time_s);
    out.push_back(q);
  }
  if (std::all_of(points.begin(), points.end(),
                  [](const TrackerPoint& p) { return p.context.has_temperature(); })) {
    Quantity q{"temperature", "K", {}};
    for (const TrackerPoint& p : points) q.values.push_back(p.context.temperature_delta_K);
    out.push_back(q);
  }
  return out;
}

void Evidence(const RobotModel& model, const std::vector<TrackerPoint>& points,
              const CrossValidation& cv, DiscoveryResult* r) {
  const std::vector<Quantity> quantities = Quantities(model, points);
  std::vector<std::vector<double>> comp(4);
  const char* names[4] = {"x", "y", "z", "norm"};
  for (const Vector3& e : cv.e) {
    for (int a = 0; a < 3; ++a) comp[a].push_back(e(a));
    comp[3].push_back(e.norm());
  }
  for (const Quantity& q : quantities) {
    for (int a = 0; a < 4; ++a) {
      r->evidence.push_back({q.name, names[a], stats::Correlation(q.values, comp[a])});
    }
    // Map: residual RMS in 8 equal bins of the quantity's range.
    ResidualMap m;
    m.quantity = q.name;
    m.unit = q.unit;
    const auto [lo_it, hi_it] = std::minmax_element(q.values.begin(), q.values.end());
    const double lo = *lo_it, hi = *hi_it;
    const int bins = hi > lo ? 8 : 1;
    std::vector<double> ss(bins, 0.0);
    m.count.assign(bins, 0);
    for (std::size_t i = 0; i < q.values.size(); ++i) {
      int b = hi > lo ? static_cast<int>((q.values[i] - lo) / (hi - lo) * bins) : 0;
      b = std::clamp(b, 0, bins - 1);
      ss[b] += cv.e[i].squaredNorm();
      ++m.count[b];
    }
    for (int b = 0; b < bins; ++b) {
      m.bin_centre.push_back(lo + (b + 0.5) * (hi - lo) / bins);
      m.rms_m.push_back(m.count[b] > 0 ? std::sqrt(ss[b] / m.count[b]) : 0.0);
    }
    r->maps.push_back(m);
  }
  std::stable_sort(r->evidence.begin(), r->evidence.end(),
                   [](const ResidualCorrelation& a, const ResidualCorrelation& b) {
                     return std::abs(a.r) > std::abs(b.r);
                   });
  if (r->evidence.size() > 8) r->evidence.resize(8);
}

}  // namespace

void ValidateDiscoveryOptions(const DiscoveryOptions& o) {
  const auto fail = [](const std::string& field, const std::string& why) {
    throw InputError("diagnosis." + field, why);
  };
  if (!(o.alpha > 0.0 && o.alpha < 0.5)) fail("alpha", "must be in (0, 0.5)");
  if (!(o.min_gain_percent >= 0.0 && o.min_gain_percent < 100.0)) {
    fail("min_gain_percent", "must be in [0, 100)");
  }
  if (o.max_effects < 0 || o.max_effects > 10) fail("max_effects", "must be from 0 to 10");
  if (o.folds < 2 || o.folds > 20) fail("folds", "must be from 2 to 20");
  if (!(o.correlation_limit > 0.0 && o.correlation_limit <= 1.0)) {
    fail("correlation_limit", "must be in (0, 1]");
  }
  if (o.jobs < 0) fail("jobs", "must be >= 0");
  if (!(o.joint_sigma_rad >= 0.0 && o.joint_sigma_rad <= 0.01)) {
    fail("joint_sigma", "must be from 0 to 0.01 rad (0.57 deg)");
  }
  ValidateIdentificationOptions(o.engine);
}

DiscoveryResult DiscoverTrackerModel(const RobotModel& start,
                                     const std::vector<TrackerPoint>& points,
                                     const DiscoveryOptions& o) {
  ValidateDiscoveryOptions(o);
  const int n = static_cast<int>(points.size());
  const int per_fold_train = n - (n + o.folds - 1) / o.folds;
  if (3 * per_fold_train <= start.num_parameters() + 6) {
    throw InputError(o.set.source, "model discovery: " + std::to_string(n) + " points leave " +
                                       std::to_string(per_fold_train) +
                                       " to train on in a fold of " + std::to_string(o.folds) +
                                       ", too few for the model's " +
                                       std::to_string(start.num_parameters()) +
                                       " parameters and the tracker pose");
  }
  const auto say = [&](const std::string& line) {
    if (o.progress) o.progress(line);
  };
  DiscoveryResult r;
  const std::vector<Matrix3> covariance = NoiseCovariances(start, points, o);
  r.noise = EstimateNoise(points, covariance, o);
  const std::vector<int> random = RandomFolds(n, o.folds, o.seed);
  const std::vector<int> region = RegionFolds(points, o.folds, &r.region_rule);
  const std::string random_rule = std::to_string(o.folds) + "-fold cross-validation, points "
                                  "assigned to folds at random (seed " + std::to_string(o.seed) +
                                  ")";

  RobotModel current = start;
  say("diagnosis: residual test of the starting model (" + std::to_string(o.folds) + " folds)");
  r.test_before = TestResiduals(CrossValidate(current, points, random, o.folds, o, "residual test"),
                                points, covariance, o, random_rule);
  CrossValidation current_region =
      CrossValidate(current, points, region, o.folds, o, "region folds");
  r.heldout_rms_start_m = current_region.Rms();
  if (!r.test_before.systematic) {
    r.verdict = "consistent_with_noise";
    std::ostringstream os;
    os << "the held-out residuals (RMS " << Mm(r.test_before.rms_m) << ") are consistent with "
       << "the noise floor (sigma " << Mm(r.noise.sigma_m) << " per axis): p = "
       << r.test_before.p_value << " >= alpha = " << o.alpha << "; no effect searched";
    r.reason = os.str();
    r.test_after = r.test_before;
    r.heldout_rms_discovered_m = r.heldout_rms_start_m;
  } else {
    const std::vector<TermSpec> all_specs =
        o.candidates.empty() ? CandidateTermSpecs(start.chain) : o.candidates;
    const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
    const int jobs = o.jobs > 0 ? o.jobs : static_cast<int>(cores);
    for (int step = 1; step <= o.max_effects; ++step) {
      const int base_rank = FitModel(current, points, o, "step base").result.observability.rank;
      DiscoveryStep s;
      s.index = step;
      s.heldout_rms_before_m = current_region.Rms();
      s.candidates.resize(all_specs.size());
      std::atomic<int> next{0}, done{0};
      std::mutex mutex;
      std::string error;
      const auto worker = [&]() {
        for (int k = next++; k < static_cast<int>(all_specs.size()); k = next++) {
          try {
            s.candidates[k] = ScoreCandidate(current, base_rank, all_specs[k], points, region,
                                             current_region, o);
          } catch (const std::exception& e) {
            s.candidates[k].spec = all_specs[k];
            s.candidates[k].label = TermLabel(all_specs[k]);
            s.candidates[k].identifiable = false;
            s.candidates[k].note = std::string("its identification failed: ") + e.what();
          }
          const int d = ++done;
          std::lock_guard<std::mutex> lock(mutex);
          say("diagnosis: step " + std::to_string(step) + ", candidate " + std::to_string(d) +
              " of " + std::to_string(all_specs.size()) + " (" + s.candidates[k].label + ")");
        }
      };
      std::vector<std::thread> pool;
      for (int t = 0; t < std::min<int>(jobs, static_cast<int>(all_specs.size())); ++t) {
        pool.emplace_back(worker);
      }
      for (std::thread& t : pool) t.join();

      // Holm over the tested candidates; the largest gain is accepted only if it passes.
      std::vector<int> tested;
      std::vector<double> p;
      for (int k = 0; k < static_cast<int>(s.candidates.size()); ++k) {
        if (s.candidates[k].tested) {
          tested.push_back(k);
          p.push_back(s.candidates[k].p_value);
        }
      }
      const std::vector<double> adjusted = stats::HolmAdjust(p);
      int best = -1;
      for (std::size_t t = 0; t < tested.size(); ++t) {
        CandidateScore& c = s.candidates[tested[t]];
        c.p_adjusted = adjusted[t];
        if (best < 0 || c.gain_percent > s.candidates[best].gain_percent) best = tested[t];
      }
      s.heldout_rms_after_m = s.heldout_rms_before_m;
      if (best >= 0) {
        CandidateScore& c = s.candidates[best];
        std::ostringstream why;
        if (c.p_adjusted >= o.alpha) {
          why << "largest held-out gain, but not significant: Holm-adjusted p = " << c.p_adjusted
              << " >= " << o.alpha << " over " << tested.size() << " candidates";
        } else if (c.gain_percent < o.min_gain_percent) {
          why << "largest held-out gain, but " << c.gain_percent << " % < the "
              << o.min_gain_percent << " % worth a term";
        } else if (c.max_geometry_correlation >= o.correlation_limit) {
          why << "largest held-out gain, but a disguise of the geometry: |rho| = "
              << c.max_geometry_correlation << " with " << c.correlated_with;
        } else {
          c.accepted = true;
          why << "accepted: largest held-out gain (" << c.gain_percent
              << " %), Holm-adjusted p = " << c.p_adjusted << " over " << tested.size()
              << " candidates";
        }
        c.note = c.note.empty() ? why.str() : c.note + "; " + why.str();
      }
      if (best < 0 || !s.candidates[best].accepted) {
        r.steps.push_back(std::move(s));
        break;
      }
      const CandidateScore& accepted = s.candidates[best];
      s.accepted = best;
      current = WithTerm(current, MakeErrorTerm(accepted.spec, start.chain, start.name()));
      current_region = CrossValidate(current, points, region, o.folds, o, "region folds");
      s.heldout_rms_after_m = current_region.Rms();
      r.effects_added.push_back(accepted);
      say("diagnosis: step " + std::to_string(step) + " added " + accepted.label +
          ", held-out RMS " + Mm(s.heldout_rms_before_m) + " -> " + Mm(s.heldout_rms_after_m));
      r.steps.push_back(std::move(s));
      // Once the residual is consistent with the noise there is nothing left to explain: a
      // further term could only fit noise.
      r.test_after = TestResiduals(
          CrossValidate(current, points, random, o.folds, o, "residual test"), points, covariance,
          o, random_rule);
      if (!r.test_after.systematic) break;
    }
    r.heldout_rms_discovered_m = current_region.Rms();
    if (r.effects_added.empty()) {
      r.test_after = r.test_before;
      r.verdict = "unexplained";
      std::ostringstream os;
      os << "the held-out residuals (RMS " << Mm(r.test_before.rms_m)
         << ") are systematic (p = " << r.test_before.p_value << " against sigma "
         << Mm(r.noise.sigma_m) << " per axis) and no candidate effect passes";
      r.reason = os.str();
    } else {
      r.verdict = "effects_added";
      std::ostringstream os;
      os << r.effects_added.size() << " effect(s) added; region-disjoint held-out RMS "
         << Mm(r.heldout_rms_start_m) << " -> " << Mm(r.heldout_rms_discovered_m)
         << "; the residual is then " << (r.test_after.systematic ? "still systematic" :
                                                                    "consistent with noise")
         << " (p = " << r.test_after.p_value << ")";
      r.reason = os.str();
    }
  }
  const Fit final_fit = FitModel(current, points, o, "discovered model, every point");
  r.model = final_fit.result.model;
  r.X_TB = final_fit.X_TB;
  Evidence(start, points, current_region, &r);
  return r;
}

}  // namespace twin
