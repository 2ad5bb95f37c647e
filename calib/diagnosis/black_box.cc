#include "calib/diagnosis/black_box.h"

#include <cmath>
#include <sstream>

#include <Eigen/Cholesky>

#include "calib/common/errors.h"
#include "calib/diagnosis/comparators.h"
#include "calib/diagnosis/discovery_folds.h"

namespace twin {
namespace {

// The RBF kernel between standardised inputs (rows of A and B).
Eigen::MatrixXd Kernel(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, double length_scale) {
  const Eigen::VectorXd a2 = A.rowwise().squaredNorm(), b2 = B.rowwise().squaredNorm();
  Eigen::MatrixXd d2 = -2.0 * A * B.transpose();
  d2.colwise() += a2;
  d2.rowwise() += b2.transpose();
  return (-d2.cwiseMax(0.0) / (2.0 * length_scale * length_scale)).array().exp().matrix();
}

// The rows `index` of M.
Eigen::MatrixXd Rows(const Eigen::MatrixXd& M, const std::vector<int>& index) {
  Eigen::MatrixXd out(index.size(), M.cols());
  for (std::size_t k = 0; k < index.size(); ++k) out.row(k) = M.row(index[k]);
  return out;
}

}  // namespace

void ValidateKernelRidgeOptions(const KernelRidgeOptions& o, const std::string& where) {
  if (o.length_scales.empty()) throw InputError(where + ".length_scales", "must not be empty");
  if (o.regularisations.empty()) throw InputError(where + ".regularisations", "must not be empty");
  for (double l : o.length_scales) {
    if (!(l > 0.0 && std::isfinite(l))) {
      throw InputError(where + ".length_scales", "must be positive, got " + std::to_string(l));
    }
  }
  for (double r : o.regularisations) {
    if (!(r > 0.0 && std::isfinite(r))) {
      throw InputError(where + ".regularisations", "must be positive, got " + std::to_string(r));
    }
  }
}

Eigen::MatrixXd KernelRidge::Predict(const Eigen::MatrixXd& inputs) const {
  const Eigen::MatrixXd z =
      (inputs.rowwise() - centre).array().rowwise() * inv_scale.array();
  return (Kernel(z, Z, length_scale) * alpha).rowwise() + mean;
}

KernelRidge FitKernelRidge(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Y,
                           double length_scale, double regularisation) {
  TWIN_REQUIRE(X.rows() == Y.rows() && X.rows() >= 1 && length_scale > 0.0 &&
                   regularisation > 0.0,
               "FitKernelRidge: " + std::to_string(X.rows()) + " inputs, " +
                   std::to_string(Y.rows()) + " outputs, l = " + std::to_string(length_scale) +
                   ", lambda = " + std::to_string(regularisation));
  KernelRidge m;
  m.length_scale = length_scale;
  m.regularisation = regularisation;
  m.centre = X.colwise().mean();
  const Eigen::MatrixXd centred = X.rowwise() - m.centre;
  const Eigen::RowVectorXd sd =
      (centred.colwise().squaredNorm() / static_cast<double>(X.rows())).cwiseSqrt();
  m.inv_scale = Eigen::RowVectorXd::Zero(X.cols());
  for (int j = 0; j < X.cols(); ++j) {
    // A joint that does not move in the training rows tells nothing: left out.
    if (sd(j) > 1e-12) m.inv_scale(j) = 1.0 / sd(j);
  }
  m.Z = centred.array().rowwise() * m.inv_scale.array();
  m.mean = Y.colwise().mean();
  Eigen::MatrixXd K = Kernel(m.Z, m.Z, length_scale);
  K.diagonal().array() += regularisation;
  m.alpha = K.llt().solve(Y.rowwise() - m.mean);
  return m;
}

KernelRidge FitKernelRidgeCV(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Y,
                             const std::vector<int>& fold_of, int folds,
                             const KernelRidgeOptions& o, double* cv_sse) {
  TWIN_REQUIRE(static_cast<int>(fold_of.size()) == X.rows() && X.rows() == Y.rows() && folds >= 1,
               "FitKernelRidgeCV: " + std::to_string(fold_of.size()) + " fold indices for " +
                   std::to_string(X.rows()) + " rows");
  // Each fold's training and held-out rows.
  std::vector<std::vector<int>> train(folds), test(folds);
  for (int i = 0; i < X.rows(); ++i) {
    for (int k = 0; k < folds; ++k) (fold_of[i] == k ? test[k] : train[k]).push_back(i);
  }
  double best = INFINITY;
  double best_l = o.length_scales.front(), best_r = o.regularisations.front();
  bool scored = false;
  for (double l : o.length_scales) {
    for (double lambda : o.regularisations) {
      double sse = 0;
      for (int k = 0; k < folds; ++k) {
        if (test[k].empty() || train[k].empty()) continue;
        const KernelRidge m = FitKernelRidge(Rows(X, train[k]), Rows(Y, train[k]), l, lambda);
        sse += (m.Predict(Rows(X, test[k])) - Rows(Y, test[k])).squaredNorm();
        scored = true;
      }
      if (sse < best) {  // strictly smaller: ties go to the first pair of the grid
        best = sse;
        best_l = l;
        best_r = lambda;
      }
    }
  }
  TWIN_REQUIRE(scored, "FitKernelRidgeCV: no fold with rows on both sides");
  if (cv_sse) *cv_sse = best;
  return FitKernelRidge(X, Y, best_l, best_r);
}

namespace discovery {
namespace {

// The joint readings of the points `index` (all when empty), one row each.
Eigen::MatrixXd JointRows(const std::vector<TrackerPoint>& points, const std::vector<int>& index) {
  const int n = index.empty() ? static_cast<int>(points.size()) : static_cast<int>(index.size());
  Eigen::MatrixXd X(n, points.front().context.q.size());
  for (int k = 0; k < n; ++k) X.row(k) = points[index.empty() ? k : index[k]].context.q.transpose();
  return X;
}

// The residual p_T - X_TB p_B of a fit at the points `index`, turned into the base frame
// (R_TB^T), one row each: what the black box learns.
Eigen::MatrixXd BaseResiduals(const Fit& fit, const std::vector<TrackerPoint>& points,
                              const std::vector<int>& index) {
  Eigen::MatrixXd Y(index.size(), 3);
  for (std::size_t k = 0; k < index.size(); ++k) {
    const TrackerPoint& p = points[index[k]];
    const Vector3 p_B = EndPose(fit.result.model, p.context).translation();
    Y.row(k) = (fit.X_TB.linear().transpose() * (p.p_T - fit.X_TB * p_B)).transpose();
  }
  return Y;
}

// The points `index` of `points`.
std::vector<TrackerPoint> Subset(const std::vector<TrackerPoint>& points,
                                 const std::vector<int>& index) {
  std::vector<TrackerPoint> out;
  for (int i : index) out.push_back(points[i]);
  return out;
}

// One region fold: the starting model fitted on the other folds, the black box on their
// residual (inner region folds of the training part), both scored on the fold.
BlackBoxFold HeldOutFold(const TrackerData& data, const RobotModel& start,
                         const std::vector<int>& train, const std::vector<int>& test, int fold,
                         int folds, const KernelRidgeOptions& options, double* sse,
                         double* sse_start) {
  const std::vector<TrackerPoint>& points = data.points();
  const Fit fit = data.FitOn(start, train, "black box, region fold " + std::to_string(fold + 1));
  const std::vector<TrackerPoint> train_points = Subset(points, train);
  std::string inner_rule;
  const int inner = std::min(folds, static_cast<int>(train.size()));
  const std::vector<int> inner_fold = RegionFolds(train_points, inner, &inner_rule);
  const KernelRidge box = FitKernelRidgeCV(JointRows(points, train),
                                           BaseResiduals(fit, points, train), inner_fold, inner,
                                           options);
  const Eigen::MatrixXd predicted = box.Predict(JointRows(points, test));
  for (std::size_t k = 0; k < test.size(); ++k) {
    const TrackerPoint& p = points[test[k]];
    const Vector3 p_B = EndPose(fit.result.model, p.context).translation();
    const Vector3 corrected = p_B + predicted.row(k).transpose();
    *sse += (fit.X_TB * corrected - p.p_T).squaredNorm();
    *sse_start += (fit.X_TB * p_B - p.p_T).squaredNorm();
  }
  return {fold + 1, static_cast<int>(train.size()), static_cast<int>(test.size()),
          box.length_scale, box.regularisation};
}

// The black box trained on every point of the first session, scored on the second.
void SessionBlackBox(const TrackerData& data, const RobotModel& start,
                     const std::vector<int>& region, int folds, const DiscoveryOptions& o,
                     BlackBoxResult* r) {
  const std::vector<TrackerPoint>& points = data.points();
  std::vector<int> all(points.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  const Fit fit = data.FitOn(start, {}, "black box, all data");
  const KernelRidge box = FitKernelRidgeCV(JointRows(points, {}), BaseResiduals(fit, points, all),
                                           region, folds, o.kernel_ridge);
  r->length_scale = box.length_scale;
  r->regularisation = box.regularisation;
  if (o.session.empty()) return;
  const std::string source = o.set.source + " (second session)";
  const Eigen::MatrixXd predicted = box.Predict(JointRows(o.session, {}));
  std::vector<Vector3> p_B;
  for (std::size_t k = 0; k < o.session.size(); ++k) {
    p_B.push_back(EndPose(fit.result.model, o.session[k].context).translation() +
                  predicted.row(k).transpose());
  }
  r->session = ScorePredictionsOnSession(
      p_B, o.session, SessionHalvings(o.session, o.session_scoring, source), source);
}

}  // namespace

BlackBoxResult TrackerBlackBox(const TrackerData& data, const RobotModel& start,
                               const std::vector<int>& region, int folds,
                               const DiscoveryOptions& o) {
  if (o.progress) o.progress("diagnosis: black box (kernel ridge) on the region folds");
  BlackBoxResult r;
  r.computed = true;
  r.trained_on = "the residual of the starting (geometric) model fitted on the training part "
                 "(its 3 components in the robot's base frame) over the joint readings; "
                 "held out: that model plus the black box's prediction";
  std::ostringstream rule;
  rule << "RBF kernel on the joint readings (each over its standard deviation in the training "
          "part); length scale and lambda from a grid by an inner " << folds
       << "-fold region-disjoint cross-validation (k-means blocks) of the training part only; "
          "the session's model chosen the same way on the diagnosis's region folds";
  r.hyperparameter_rule = rule.str();
  const int n = data.size();
  double sse = 0, sse_start = 0;
  for (int k = 0; k < folds; ++k) {
    std::vector<int> train, test;
    for (int i = 0; i < n; ++i) (region[i] == k ? test : train).push_back(i);
    if (test.empty()) continue;
    r.folds.push_back(
        HeldOutFold(data, start, train, test, k, folds, o.kernel_ridge, &sse, &sse_start));
  }
  r.heldout_rms_m = std::sqrt(sse / n);
  r.heldout_rms_start_m = std::sqrt(sse_start / n);
  SessionBlackBox(data, start, region, folds, o, &r);
  return r;
}

}  // namespace discovery
}  // namespace twin
