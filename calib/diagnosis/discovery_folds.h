// The folds of model discovery's cross-validations (internal to calib/diagnosis): random folds
// for the residual test of tracker points, region folds for the candidates' scores (workspace
// blocks of tracker points by k-means; whole optical axes). Each returns every unit's fold,
// 0..k-1 (model_discovery.h, steps 2 and 3).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "calib/measurements/tracker_set.h"

namespace twin::discovery {

/// n units dealt to k folds in a random order (seed): fold sizes differ by at most one.
/// Requires n >= 0, k >= 1.
std::vector<int> RandomFolds(int n, int k, std::uint64_t seed);

/// k workspace blocks: k-means (Lloyd) on the measured points, started from the point nearest
/// the centroid and then each time the point farthest from the centres so far (deterministic).
/// `rule` says how the blocks were made, with their sizes. Requires k >= 1 and a point.
std::vector<int> RegionFolds(const std::vector<TrackerPoint>& points, int k, std::string* rule);

/// k folds of whole optical axes, consecutive plan axes together: the sample of axis a (its
/// rank r among the q distinct axes, ascending) goes to fold r k / q. `sample_axes`: each
/// sample's axis index. Requires 1 <= k <= q.
std::vector<int> AxisFolds(const std::vector<int>& sample_axes, int k, std::string* rule);

}  // namespace twin::discovery
