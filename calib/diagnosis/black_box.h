// A black-box comparator beside the diagnosis's verdict (issue 39, item 7): kernel ridge
// regression of the starting (geometric) model's residual, its 3 components in the robot's
// base frame, over the joint readings, with an RBF kernel. It stands in for the physics terms:
// how far does a model that knows nothing of physics get on the same held-out data? It is
// scored on the diagnosis's own region folds and, with a second session, on that session as
// the models are (session_scoring.h); it is never part of the delivered model.
//
// The kernel: k(x, x') = exp(-|z - z'|^2 / (2 l^2)), z the joint readings each divided by its
// standard deviation over the rows trained on (a joint that does not move there is left out).
// Weights: (K + lambda I) alpha = Y - mean(Y); prediction mean(Y) + k(z, Z) alpha. Its
// hyperparameters l and lambda are chosen by an inner cross-validation on the training part
// only, over region folds of it (k-means blocks of its measured points, as the outer folds):
// the outer score asks for predictions in a region the training never saw, and random inner
// folds would reward the short length scale that only interpolates. A grid, not a gradient
// search (few values, deterministic, the same on every machine); ties go to the first pair.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "calib/diagnosis/session_scoring.h"

namespace twin {

struct KernelRidgeOptions {
  /// Candidate length scales, in units of each joint's standard deviation over the rows
  /// trained on [-]
  std::vector<double> length_scales = {0.25, 0.5, 1.0, 2.0, 4.0, 8.0};
  /// Candidate regularisations lambda, relative to the kernel's unit diagonal (a noise to
  /// signal variance ratio) [-]
  std::vector<double> regularisations = {1e-4, 1e-3, 1e-2, 1e-1, 1.0};
};

/// Throws InputError naming the bad field (`where`.length_scales, ...).
void ValidateKernelRidgeOptions(const KernelRidgeOptions& options, const std::string& where);

/// A fitted kernel ridge regression from inputs (rows) to outputs (columns).
struct KernelRidge {
  Eigen::RowVectorXd centre;     ///< inputs' mean over the training rows
  Eigen::RowVectorXd inv_scale;  ///< 1 / their standard deviation; 0 for a constant input
  Eigen::MatrixXd Z;             ///< the standardised training inputs
  Eigen::MatrixXd alpha;         ///< dual weights, one column per output
  Eigen::RowVectorXd mean;       ///< outputs' mean over the training rows (the prior mean)
  double length_scale = 1.0;     ///< [-], standardised units
  double regularisation = 1e-3;  ///< lambda [-]

  /// Predicted outputs at `inputs` (one row each).
  Eigen::MatrixXd Predict(const Eigen::MatrixXd& inputs) const;
};

/// Fits with the given hyperparameters. Requires X.rows() == Y.rows() >= 1, length_scale > 0,
/// regularisation > 0.
KernelRidge FitKernelRidge(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Y,
                           double length_scale, double regularisation);

/// The hyperparameter pair of the options' grid with the smallest held-out sum of squares over
/// the inner folds (`fold_of`: each row's fold 0..folds-1; an empty fold is skipped), then
/// fitted on every row with it. `cv_sse`, when given, receives that sum [output units^2].
/// Requires valid options and a fold with rows on both sides.
KernelRidge FitKernelRidgeCV(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Y,
                             const std::vector<int>& fold_of, int folds,
                             const KernelRidgeOptions& options, double* cv_sse = nullptr);

/// The hyperparameters one region fold's black box was fitted with.
struct BlackBoxFold {
  int fold = 0;           ///< 1-based, as the diagnosis's region folds
  int training = 0, scored = 0;  ///< points
  double length_scale = 0, regularisation = 0;
};

/// The comparator's result (DiscoveryResult::black_box).
struct BlackBoxResult {
  bool computed = false;
  std::string note;             ///< why not computed (empty when computed)
  std::string trained_on;       ///< what its targets are
  std::string hyperparameter_rule;
  /// Region-disjoint held-out RMS of the starting model plus the black box (the diagnosis's
  /// folds; per fold trained on the others' residual of the starting model fitted on them) [m]
  double heldout_rms_m = std::numeric_limits<double>::quiet_NaN();
  /// The starting model alone on the same fits: the black box's base [m]
  double heldout_rms_start_m = std::numeric_limits<double>::quiet_NaN();
  std::vector<BlackBoxFold> folds;
  /// Chosen on every point of the first session (the model the second session is scored
  /// with) [-]
  double length_scale = std::numeric_limits<double>::quiet_NaN();
  double regularisation = std::numeric_limits<double>::quiet_NaN();
  /// The second session: the starting model's prediction plus the black box's at its joint
  /// readings, the tracker pose refitted per halving; empty without a second session.
  std::optional<SessionScore> session;
};

}  // namespace twin
