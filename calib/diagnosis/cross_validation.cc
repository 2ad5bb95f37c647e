#include "calib/diagnosis/cross_validation.h"

#include <numeric>

#include "calib/common/errors.h"
#include "calib/diagnosis/statistics.h"

namespace twin::discovery {

CrossValidation CrossValidate(const Data& data, const RobotModel& model,
                              const std::vector<int>& fold_of, int folds,
                              const std::string& what) {
  const int n = data.size();
  TWIN_REQUIRE(static_cast<int>(fold_of.size()) == n && folds >= 1,
               "CrossValidate: " + std::to_string(fold_of.size()) + " fold indices for " +
                   std::to_string(n) + " units in " + std::to_string(folds) + " folds");
  CrossValidation cv;
  cv.Resize(n);
  for (int k = 0; k < folds; ++k) {
    std::vector<int> train, test;
    for (int i = 0; i < n; ++i) (fold_of[i] == k ? test : train).push_back(i);
    if (test.empty()) continue;
    const Fit fit = data.FitOn(model, train, what + ", fold " + std::to_string(k + 1));
    data.HeldOut(fit, test, &cv);
    cv.unknowns += fit.result.unknowns / static_cast<double>(folds);
    cv.train_rows += data.Rows(train) / folds;
  }
  return cv;
}

ResidualTest TestResiduals(const CrossValidation& cv, const DiscoveryOptions& o,
                           const std::string& held_out) {
  TWIN_REQUIRE(cv.dof > 0.0, "TestResiduals: " + std::to_string(cv.dof) + " dof");
  ResidualTest t;
  t.held_out = held_out;
  t.points = static_cast<int>(cv.e.size());
  t.rms_m = cv.Rms();
  const double chi2 = std::accumulate(cv.chi2.begin(), cv.chi2.end(), 0.0);
  t.dof = cv.dof;
  t.inflation = cv.train_rows > 0 ? 1.0 + cv.unknowns / cv.train_rows : 1.0;
  t.statistic = chi2 / t.inflation;
  t.p_value = stats::ChiSquareUpperTail(t.statistic, t.dof);
  t.systematic = t.p_value < o.alpha;
  return t;
}

ResidualTest RunResidualTest(const Data& data, const RobotModel& model,
                             const std::vector<int>& folds_of, int folds,
                             const DiscoveryOptions& o, const std::string& rule,
                             const std::string& what) {
  const CrossValidation cv = data.GlobalTest()
                                 ? data.InSample(model, what + ", every sample")
                                 : CrossValidate(data, model, folds_of, folds, what);
  if (!(cv.dof > 0.0)) {
    // A user's few samples on many unknowns: bad input, not a bug.
    throw InputError(data.source(), "model discovery, " + what + ": " +
                                        std::to_string(static_cast<int>(cv.dof)) +
                                        " degrees of freedom; too few units of data for the "
                                        "model's unknowns");
  }
  return TestResiduals(cv, o, rule);
}

}  // namespace twin::discovery
