#include "calib/diagnosis/candidate_scoring.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>

#include <Eigen/Eigenvalues>

#include "calib/common/errors.h"
#include "calib/common/frames.h"
#include "calib/diagnosis/cross_validation.h"
#include "calib/diagnosis/statistics.h"
#include "calib/identification/dormant_restart.h"
#include "calib/identification/observability.h"
#include "calib/model/end_point_jacobian.h"
#include "calib/model/parameter_layout.h"

namespace twin::discovery {

void SizeTest(const IdentificationResult& fit, int first, const ErrorTerm& term, double session_s,
              CandidateScore* c) {
  const int n = static_cast<int>(term.parameters().size());
  if (n <= 0 || fit.covariance.rows() < first + n) return;
  Eigen::VectorXd p(n);
  for (int k = 0; k < n; ++k) p(k) = fit.parameters[first + k].estimated;
  Eigen::MatrixXd J;
  const Eigen::VectorXd size = term.SizeMeasures(p.data(), session_s, &J);
  const stats::WaldTest w =
      stats::WaldTestZero(size, J * fit.covariance.block(first, first, n, n) * J.transpose());
  c->size_statistic = w.statistic;
  c->size_dof = w.dof;
  c->size_p_value = w.p_value;
}

bool HasDormantParameters(const TermSpec& spec, const RobotModel& start) {
  return MakeErrorTerm(spec, start.chain, start.name())->has_dormant_parameters();
}

bool BuildCandidateModel(const Data& data, const RobotModel& base, const TermSpec& spec,
                         RobotModel* model, CandidateScore* c) {
  try {
    *model = WithTerm(base, MakeErrorTerm(spec, base.chain, base.name(), "candidate " + c->label));
  } catch (const InputError& e) {
    c->applicable = false;
    c->note = e.what();
    return false;
  }
  for (int i = 0; i < data.size(); ++i) {
    const std::string missing = MissingContext(*model, data.context(i));
    if (!missing.empty()) {
      c->applicable = false;
      c->note = "not applicable: " + missing + " (" + data.Where(i) + ")";
      return false;
    }
  }
  return true;
}

CandidateFit FitCandidate(const Data& data, RobotModel model, int base_rank, CandidateScore* c) {
  CandidateFit f;
  f.added = static_cast<int>(model.terms.back()->parameters().size());
  f.first = model.num_parameters() - f.added;
  c->driver = model.terms.back()->driver();
  const bool dormant = model.terms.back()->has_dormant_parameters();
  const int added = f.added;
  const auto fit = [&](const RobotModel& m, bool restart) {
    return data.FitOn(m, {},
                      "candidate " + c->label + ", all data" + (restart ? ", restarted" : ""));
  };
  // Some parameters only have a gradient once the term acts (a time constant while the
  // amplitude is zero): where the rank rose but not by the term's parameters, start again
  // from the first solution's term values, and keep that start (for the cross-validation too)
  // where KeepRestart says so.
  const auto wake = [&](const RobotModel& m,
                        const IdentificationResult& first) -> std::optional<RobotModel> {
    const int rank = first.observability.rank;
    if (!dormant || rank <= base_rank || rank >= base_rank + added) return std::nullopt;
    RobotModel restart = m;
    restart.term_values.tail(added) = first.model.term_values.tail(added);
    return restart;
  };
  DormantRestart<Fit> kept = FitWithDormantRestart<Fit>(model, fit, wake);
  f.model = std::move(kept.model);
  f.all = std::move(kept.fit);
  f.rank = f.all.result.observability.rank;
  c->restarted = kept.restarted;
  return f;
}

void RecordParametersAndSize(const Data& data, const CandidateFit& f, CandidateScore* c) {
  for (int k = 0; k < f.added; ++k) {
    const IdentifiedParameter& ip = f.all.result.parameters[f.first + k];
    c->parameters.push_back({ip.name, ip.unit, ip.estimated, ip.sigma});
  }
  double session_s = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < data.size(); ++i) {
    const MeasurementContext& x = data.context(i);
    if (x.has_time() && (std::isnan(session_s) || x.time_s > session_s)) session_s = x.time_s;
  }
  SizeTest(f.all.result, f.first, *f.model.terms.back(), session_s, c);
}

bool RaisesRank(const Data& data, const CandidateFit& f, int base_rank, CandidateScore* c) {
  if (f.rank <= base_rank) {
    c->identifiable = false;
    c->note = "unidentifiable from " + data.Measured() + ": the rank does not rise with its " +
              std::to_string(f.added) + " parameter(s) (the measurements cannot tell it from "
              "the geometry, or it has nothing to act on)";
    return false;
  }
  if (f.rank < base_rank + f.added) {
    // Partly identifiable (e.g. a mount deflection along the flange axis is the tool length's):
    // the engine identifies only the combinations the data sees, the rest stay at zero.
    c->note = "partly identifiable: the rank rises by " + std::to_string(f.rank - base_rank) +
              " of its " + std::to_string(f.added) + " parameters";
  }
  return true;
}

namespace {

// The engine's TermGeometryDependence of the candidate (the last block of its model), or null
// where the fit did not compute one.
const TermGeometryDependence* TermDependenceOf(const CandidateFit& f) {
  const std::string block = ParameterLayout(f.model).blocks().back().name;
  for (const TermGeometryDependence& d : f.all.result.term_dependence) {
    if (d.block == block) return &d;
  }
  return nullptr;
}

}  // namespace

void MeasureGeometryDisguise(const CandidateFit& f, int base_rank, CandidateScore* c) {
  if (const TermGeometryDependence* found = TermDependenceOf(f)) {
    const TermGeometryDependence& d = *found;
    const int rise = f.rank - base_rank;
    const int skip = std::max(0, static_cast<int>(d.canonical_correlations.size()) - rise);
    if (skip < static_cast<int>(d.canonical_correlations.size())) {
      c->max_geometry_correlation = d.canonical_correlations[skip];
      c->correlated_with = d.nearest_geometric[skip];
      c->geometry_correlations.assign(d.canonical_correlations.begin() + skip,
                                      d.canonical_correlations.end());
      c->min_geometry_correlation = c->geometry_correlations.back();
    }
  }
}

namespace {

// The end point's displacement at every unit of `data`, stacked (3 rows a unit), per unit of
// the term's first m parameters (E), with the other parameters' compensating response
// (TermGeometryDependence::compensation), then less the best rigid motion of all the points
// (the scores are taken after a rigid alignment, and a rigid motion of everything is what a
// tracker's pose or a cell's frame absorbs); E_raw: the term's own columns. Returns
// A = E'E / units and A_raw = E_raw'E_raw / units.
void EndPointMoves(const Data& data, const CandidateFit& f, const TermGeometryDependence& d,
                   int m, Eigen::MatrixXd* A, Eigen::MatrixXd* A_raw) {
  const RobotModel& model = f.all.result.model;
  const Eigen::VectorXd params = GetParameters(model);
  const int n = data.size();
  Eigen::MatrixXd E(3 * n, m), E_raw(3 * n, m), rigid(3 * n, 6);
  for (int i = 0; i < n; ++i) {
    Vector3 p;
    PointJacobian J;
    EndPointJacobian(model, params.data(), data.context(i), &p, &J);
    E_raw.middleRows(3 * i, 3) = J.middleCols(f.first, m);
    Eigen::MatrixXd e = E_raw.middleRows(3 * i, 3);
    for (std::size_t r = 0; r < d.others.size(); ++r) {
      e -= J.col(d.others[r]) * d.compensation.row(static_cast<Eigen::Index>(r)).head(m);
    }
    E.middleRows(3 * i, 3) = e;
    rigid.block<3, 3>(3 * i, 0).setIdentity();
    rigid.block<3, 3>(3 * i, 3) = -SkewMatrix(p);  // a small turn w moves p by w x p
  }
  const Eigen::MatrixXd Q = SpanBasis(rigid, /*unit_columns=*/true);
  E -= Q * (Q.transpose() * E);
  *A = E.transpose() * E / n;
  *A_raw = E_raw.transpose() * E_raw / n;
}

// The size test's statistic on tracker points with a stated joint noise. The fit weighs each
// point by its sigma alone (TrackerData::FitOn), while the encoders' noise moves the point
// along the joint-angle directions (TrackerData::covariance: sigma_i^2 I + sigma_q^2 J J'):
// noise that a term acting through the joint angles (a transmission error) partly fits, so a
// statistic scaled by the fit's sigma0 overstates such a term's size. Here the term's
// columns on its seen directions U (m x k), weighed by 1 / sigma_i and less their span with
// the other free parameters and a rigid motion of all the points (the tracker's pose), give
// W = E'E and B = sum_i E_i' (S_i / sigma_i^2) E_i; the fitted theta then has covariance
// W^-1 B W^-1 (the sandwich of weighted least squares under the points' full covariance), and
// the statistic is theta_U' W B^-1 W theta_U against the stated noise (the residual test has
// checked that noise: the screen's alarm reads this only where it passed).
double TrackerSizeStatistic(const TrackerData& data, const CandidateFit& f,
                            const TermGeometryDependence& d, const Eigen::MatrixXd& U,
                            const Eigen::VectorXd& theta) {
  const RobotModel& model = f.all.result.model;
  const Eigen::VectorXd params = GetParameters(model);
  const int n = data.size(), m = static_cast<int>(U.rows()), o = static_cast<int>(d.others.size());
  Eigen::MatrixXd T(3 * n, m), M(3 * n, o + 6);
  for (int i = 0; i < n; ++i) {
    Vector3 p;
    PointJacobian J;
    EndPointJacobian(model, params.data(), data.context(i), &p, &J);
    const double w = 1.0 / data.Sigma(i);
    T.middleRows(3 * i, 3) = w * J.middleCols(f.first, m);
    for (int r = 0; r < o; ++r) M.block(3 * i, r, 3, 1) = w * J.col(d.others[r]);
    M.block<3, 3>(3 * i, o) = w * Matrix3::Identity();
    M.block<3, 3>(3 * i, o + 3) = -w * SkewMatrix(p);
  }
  const Eigen::MatrixXd Q = SpanBasis(M, /*unit_columns=*/true);
  const Eigen::MatrixXd E = (T - Q * (Q.transpose() * T)) * U;
  const int k = static_cast<int>(U.cols());
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(k, k), B = Eigen::MatrixXd::Zero(k, k);
  for (int i = 0; i < n; ++i) {
    const Eigen::MatrixXd Ei = E.middleRows(3 * i, 3);
    const double s = data.Sigma(i);
    W += Ei.transpose() * Ei;
    B += Ei.transpose() * (data.covariance()[i] / (s * s)) * Ei;
  }
  const Eigen::VectorXd g = W * (U.transpose() * theta);
  return g.dot(B.ldlt().solve(g));
}

}  // namespace

void MeasureDetectionLimit(const Data& data, const CandidateFit& f, double alpha,
                           CandidateScore* c) {
  const TermGeometryDependence* d = TermDependenceOf(f);
  // Over the term's amplitudes, its shape parameters (a warm-up's time constant) held as
  // fitted: a shape acts only through an amplitude, and one the data tell from zero is
  // ErrorTerm::SizeMeasures' business, not a hiding place of its own.
  const int m = f.model.terms.back()->amplitude_parameters();
  if (d == nullptr || m <= 0 || d->visible_information.rows() != f.added || data.size() == 0) {
    return;
  }
  const Eigen::MatrixXd V = d->visible_information.topLeftCorner(m, m);
  const RobotModel& model = f.all.result.model;
  Eigen::MatrixXd A, A_raw;
  EndPointMoves(data, f, *d, m, &A, &A_raw);
  // Directions of the term the measurements see (eigenvalues of V above a relative cut of
  // its own columns' scale) and those they do not.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(V);
  const double cut = 1e-10 * std::max(d->raw_information_scale,
                                      std::numeric_limits<double>::min());
  std::vector<int> seen;
  for (int k = 0; k < m; ++k) {
    const Eigen::VectorXd u = es.eigenvectors().col(k);
    if (es.eigenvalues()(k) > cut) {
      seen.push_back(k);
      continue;
    }
    // Unseen: does it move the end point at all (beside the term's other directions), and
    // by more than 1e-3 of what it moves without the compensation (numerical noise of the
    // projection)? A direction that moves nothing (a time constant while its amplitude is
    // zero) hides nothing.
    const double moved = u.dot(A * u), raw = u.dot(A_raw * u);
    if (raw > 1e-12 * A_raw.diagonal().maxCoeff() && moved > 1e-6 * raw) {
      c->detection_limit_m = std::numeric_limits<double>::infinity();
      return;
    }
  }
  if (seen.empty()) {
    c->detection_limit_m = 0.0;  // nothing the data cannot see, and nothing that moves
    return;
  }
  // The size test on the seen directions, at the fitted amplitudes.
  const Eigen::VectorXd theta = model.term_values.tail(f.added).head(m);
  const auto* tracker = dynamic_cast<const TrackerData*>(&data);
  if (tracker != nullptr && tracker->joint_sigma_rad() > 0.0) {
    Eigen::MatrixXd U(m, seen.size());
    for (std::size_t k = 0; k < seen.size(); ++k) U.col(k) = es.eigenvectors().col(seen[k]);
    c->visible_size_statistic = TrackerSizeStatistic(*tracker, f, *d, U, theta);
  } else {
    const double s0 = f.all.result.sigma0 > 0.0 ? f.all.result.sigma0 : 1.0;
    double statistic = 0.0;
    for (int k : seen) {
      const double along = es.eigenvectors().col(k).dot(theta);
      statistic += es.eigenvalues()(k) * along * along;
    }
    c->visible_size_statistic = statistic / (s0 * s0);
  }
  c->visible_size_dof = static_cast<int>(seen.size());
  c->visible_size_p_value = stats::ChiSquareUpperTail(c->visible_size_statistic,
                                                      c->visible_size_dof);
  // max theta' A theta subject to theta' V theta = lambda0, over the seen directions.
  Eigen::MatrixXd W(m, seen.size());
  for (std::size_t k = 0; k < seen.size(); ++k) {
    W.col(k) = es.eigenvectors().col(seen[k]) / std::sqrt(es.eigenvalues()(seen[k]));
  }
  const Eigen::MatrixXd M = W.transpose() * A * W;
  const double mu = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(M).eigenvalues().maxCoeff();
  const double z = stats::NormalUpperQuantile(0.5 * alpha) + stats::NormalUpperQuantile(0.2);
  c->detection_limit_m = std::sqrt(std::max(0.0, mu)) * z;
}

void TestHeldOut(const Data& data, const RobotModel& model, const std::vector<int>& region,
                 int folds, const CrossValidation& base_cv, CandidateScore* c) {
  const CrossValidation cv = CrossValidate(data, model, region, folds, "candidate " + c->label);
  c->heldout_rms_m = cv.Rms();
  const double base_sse = base_cv.Sse();
  c->gain_percent = base_sse > 0 ? 100.0 * (1.0 - cv.Sse() / base_sse) : 0.0;
  std::vector<double> d(cv.loss.size());
  for (std::size_t i = 0; i < d.size(); ++i) d[i] = base_cv.loss[i] - cv.loss[i];
  c->p_value = stats::WilcoxonSignedRankGreater(d).p_value;
  c->heldout_loss = cv.loss;
  c->heldout_change.clear();
  for (std::size_t i = 0; i < cv.e.size() && i < base_cv.e.size(); ++i) {
    if (cv.e[i].size() != base_cv.e[i].size()) continue;
    for (Eigen::Index r = 0; r < cv.e[i].size(); ++r) {
      c->heldout_change.push_back(base_cv.e[i](r) - cv.e[i](r));
    }
  }
  c->tested = true;
}

CandidateScore ScoreCandidate(const Data& data, const RobotModel& base, int base_rank,
                              const TermSpec& spec, const std::vector<int>& region, int folds,
                              const CrossValidation& base_cv, bool cross_validate, double alpha) {
  CandidateScore c;
  c.spec = spec;
  c.label = TermLabel(spec);
  // The base with the term, where it applies to the data.
  RobotModel model;
  if (!BuildCandidateModel(data, base, spec, &model, &c)) return c;
  // Its fit on all the data, restarted where dormant parameters need it.
  const CandidateFit fit = FitCandidate(data, std::move(model), base_rank, &c);
  // Its parameters and whether its size is told from zero.
  RecordParametersAndSize(data, fit, &c);
  // How large an effect of it the data could miss, at the end point.
  MeasureDetectionLimit(data, fit, alpha, &c);
  // Identifiable at all (the rank rises)?
  if (!RaisesRank(data, fit, base_rank, &c)) return c;
  // How nearly it is the geometry in disguise.
  MeasureGeometryDisguise(fit, base_rank, &c);
  if (!cross_validate) {
    c.note = (c.note.empty() ? "" : c.note + "; ") +
             "fitted on all the data, not tested: the residual is consistent with the noise";
    return c;
  }
  // Held out in the region folds against the base.
  TestHeldOut(data, fit.model, region, folds, base_cv, &c);
  return c;
}

std::vector<CandidateScore> ScoreAll(const Data& data, const RobotModel& current, int base_rank,
                                     const std::vector<TermSpec>& specs,
                                     const std::vector<int>& region, int folds,
                                     const CrossValidation& base_cv, bool cross_validate,
                                     double alpha, int jobs,
                                     const std::function<void(const std::string&)>& say,
                                     const std::string& what) {
  TWIN_REQUIRE(jobs >= 1, "ScoreAll: " + std::to_string(jobs) + " jobs");
  std::vector<CandidateScore> out(specs.size());
  std::atomic<int> next{0}, done{0};
  std::mutex mutex;
  // The first bug (anything but a refusal of the data) of any worker, rethrown after the join:
  // a bug is never turned into a candidate's note.
  std::exception_ptr bug;
  const auto worker = [&]() {
    for (int k = next++; k < static_cast<int>(specs.size()); k = next++) {
      try {
        out[k] = ScoreCandidate(data, current, base_rank, specs[k], region, folds, base_cv,
                                cross_validate, alpha);
      } catch (const InputError& e) {
        out[k].spec = specs[k];
        out[k].label = TermLabel(specs[k]);
        out[k].identifiable = false;
        out[k].note = std::string("its identification failed: ") + e.what();
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!bug) bug = std::current_exception();
        next = static_cast<int>(specs.size());  // no further candidates
        return;
      }
      const int d = ++done;
      std::lock_guard<std::mutex> lock(mutex);
      say("diagnosis: " + what + ", candidate " + std::to_string(d) + " of " +
          std::to_string(specs.size()) + " (" + out[k].label + ")");
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < std::min<int>(jobs, static_cast<int>(specs.size())); ++t) {
    pool.emplace_back(worker);
  }
  for (std::thread& t : pool) t.join();
  if (bug) std::rethrow_exception(bug);
  return out;
}

}  // namespace twin::discovery
