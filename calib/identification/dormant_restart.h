// The dormant-term restart, one rule for every caller (model discovery's candidates and
// declared terms, the tracker calibration's start). Some term parameters act only once others
// are non-zero (ErrorTerm::has_dormant_parameters: a warm-up's time constant has no gradient
// while its growth is zero), so a fit from zero leaves them where they started. The restart
// fits again from the first solution's values of those terms and keeps that start iff it
// identifies more (the observability rank rises) and fits no worse: its Ceres cost on the same
// data (IdentificationResult::cost_after, the weighted objective both fits minimise) at most
// kRestartCostSlack above the first's. (A restart can run off to another minimum: a warm-up
// whose time constant fell to seconds, a step that the geometry's scale absorbs.)
#pragma once

#include <optional>
#include <utility>

#include "calib/identification/engine.h"
#include "calib/model/robot_model.h"

namespace twin {

/// Relative slack of "no worse": the two solves stop at their own tolerances, so equal minima
/// differ in the last digits of the cost [-].
inline constexpr double kRestartCostSlack = 1e-6;

/// Whether a restart's fit `again` is kept over the first fit `first` of the same data: its
/// observability rank is higher and its cost_after at most (1 + kRestartCostSlack) times the
/// first's.
bool KeepRestart(const IdentificationResult& first, const IdentificationResult& again);

/// The declared terms' restart (HasDormantTermsAtZero): `start` with those terms' values from
/// the first solution (WithDormantTermsFrom); nullopt where no dormant term sleeps at zero.
std::optional<RobotModel> WithDormantTermsWoken(const RobotModel& start,
                                                const IdentificationResult& first);

/// The start kept and its fit.
template <typename FitResult>
struct DormantRestart {
  RobotModel model;        ///< the start kept: the caller's or the restart
  FitResult fit;           ///< its fit
  bool restarted = false;  ///< the restart was kept
};

/// Fits `start` with `fit` (a callable (const RobotModel&, bool restart) -> FitResult, where
/// FitResult has a member `result`, the IdentificationResult; `restart` says which fit it is,
/// for messages); where `wake` (a callable (const RobotModel& start, const
/// IdentificationResult& first) -> std::optional<RobotModel>) gives a restart, fits that too
/// and keeps it where KeepRestart says so.
template <typename FitResult, typename FitFn, typename WakeFn>
DormantRestart<FitResult> FitWithDormantRestart(const RobotModel& start, const FitFn& fit,
                                                const WakeFn& wake) {
  DormantRestart<FitResult> out{start, fit(start, false), false};
  std::optional<RobotModel> restart = wake(start, out.fit.result);
  if (!restart) return out;
  FitResult again = fit(*restart, true);
  if (KeepRestart(out.fit.result, again.result)) {
    out.model = std::move(*restart);
    out.fit = std::move(again);
    out.restarted = true;
  }
  return out;
}

}  // namespace twin
