// Model discovery's cross-validation and residual test (internal to calib/diagnosis;
// model_discovery.h, step 2): every unit predicted by the model trained without its fold, and
// the chi-square of those held-out residuals against the noise floor.
#pragma once

#include <string>
#include <vector>

#include "calib/diagnosis/discovery_data.h"

namespace twin::discovery {

/// The held-out residuals of `model` over the folds (`fold_of`: each unit's fold, 0..folds-1;
/// a fold without units is skipped): each fold's units scored by the fit on the others. The
/// unknowns and training rows are their means over all `folds`. `what` names the fits.
CrossValidation CrossValidate(const Data& data, const RobotModel& model,
                              const std::vector<int>& fold_of, int folds,
                              const std::string& what);

/// The residual test of a cross-validation: its chi-square divided by the expected inflation
/// 1 + unknowns / train_rows (1 without training rows) against chi-square(dof), systematic
/// where p < alpha. Requires cv.dof > 0.
ResidualTest TestResiduals(const CrossValidation& cv, const DiscoveryOptions& o,
                           const std::string& held_out);

/// The residual test of `model` (step 2): held out in the folds `folds_of` or, where the data
/// says so (Data::GlobalTest), the adjustment's global test. Throws InputError where the data
/// leave no degrees of freedom for it (too few units for the model's unknowns).
ResidualTest RunResidualTest(const Data& data, const RobotModel& model,
                             const std::vector<int>& folds_of, int folds,
                             const DiscoveryOptions& o, const std::string& rule,
                             const std::string& what);

}  // namespace twin::discovery
