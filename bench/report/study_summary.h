// The statistics of a Monte Carlo study: summary.json from the records of trials.jsonl
// (bench/report/trial_record.h). Keys of the summary:
//   scenario.{names,hashes}     what was studied (one of each unless shards were mixed)
//   renderers.<back end>        trials per GL back end they rendered with (the records'
//                               run.timing["timing_s.cell.renderer"]; sim/render/gl_context.h)
//   trials.{recorded,ok,failed,first,last,failures[]}   failures: {trial, reason}
//   figures.<key>               over the ok trials, for every figure of the records:
//                               {n, mean, std, median, p5, p95, min, max, ci95_mean[2]}
//                               (booleans count as 0 / 1: the mean is the fraction true)
//   parameter_errors.<robot>.<parameter>   estimated - true deviation from nominal of each
//                               named parameter (robots.<r>.parameters[]): {unit, stats...}
//   coverage.<robot>            the coverage check of the reported uncertainty: for each
//                               identifiable combination (robots.<r>.identifiable_combinations.
//                               items[i], the coordinates the identification estimates, with
//                               the 1-sigma of calib/identification/identification_covariance.h)
//                               the fraction of trials with |estimated - true| <= 1 sigma and
//                               <= 2 sigma: {combinations[]: {index, n, within_1_sigma,
//                               within_2_sigma, rms_normalized_error}, pooled: {...,
//                               within_1_sigma_interval95[2], within_2_sigma_interval95[2]},
//                               expected: {within_1_sigma: 0.683, within_2_sigma: 0.954}}
//   detection                   studies of discovery scenarios: per effect, trials where the
//                               effect was present and named / present and missed / absent and
//                               named (false), from figures discovery.effects[<effect>].
//                               {present,named}; absent when no record has them
// Percentiles interpolate linearly between order statistics (R's type 7); the confidence
// interval of the mean is mean -+ t(0.975, n-1) std / sqrt(n); the intervals of the coverage
// fractions are Wilson score intervals.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace twin {

/// Statistics of one figure over trials.
struct FigureStats {
  int n = 0;
  double mean = 0, std = 0, median = 0, p5 = 0, p95 = 0, min = 0, max = 0;
  double ci95_low = 0, ci95_high = 0;  ///< 95 % confidence interval of the mean (NaN for n 1)
};

/// The statistics of `values` (n >= 1; std is the sample standard deviation, 0 for n = 1).
FigureStats ComputeFigureStats(std::vector<double> values);

/// The p-quantile (0 <= p <= 1) of sorted values, linear between order statistics (type 7).
double Quantile(const std::vector<double>& sorted, double p);

/// The 0.975 quantile of Student's t distribution with `dof` >= 1 degrees of freedom.
double StudentT975(int dof);

/// Wilson score interval (95 %) of a fraction k / n.
void WilsonInterval95(int k, int n, double* low, double* high);

/// summary.json of the records (see above).
nlohmann::json SummarizeStudy(const std::vector<nlohmann::json>& records);

}  // namespace twin
