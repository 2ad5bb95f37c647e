#include "calib/diagnosis/discovery_folds.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <random>
#include <sstream>

#include "calib/common/errors.h"

namespace twin::discovery {

std::vector<int> RegionFolds(const std::vector<TrackerPoint>& points, int k, std::string* rule) {
  const int n = static_cast<int>(points.size());
  // More blocks than points leaves some empty (a fold without test points is skipped).
  TWIN_REQUIRE(k >= 1 && n >= 1, "RegionFolds: " + std::to_string(k) + " blocks of " +
                                     std::to_string(n) + " points");
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
  TWIN_REQUIRE(n >= 0 && k >= 1, "RandomFolds: " + std::to_string(n) + " units in " +
                                     std::to_string(k) + " folds");
  std::vector<int> index(n);
  std::iota(index.begin(), index.end(), 0);
  std::mt19937_64 rng(seed);
  std::shuffle(index.begin(), index.end(), rng);
  std::vector<int> fold(n);
  for (int r = 0; r < n; ++r) fold[index[r]] = r % k;
  return fold;
}

std::vector<int> AxisFolds(const std::vector<int>& sample_axes, int k, std::string* rule) {
  std::vector<int> axes = sample_axes;
  std::sort(axes.begin(), axes.end());
  axes.erase(std::unique(axes.begin(), axes.end()), axes.end());
  const int q = static_cast<int>(axes.size());
  TWIN_REQUIRE(k >= 1 && k <= q, "AxisFolds: " + std::to_string(k) + " folds of " +
                                     std::to_string(q) + " axes");
  std::vector<int> fold;
  for (int axis : sample_axes) {
    const int r = static_cast<int>(std::lower_bound(axes.begin(), axes.end(), axis) - axes.begin());
    fold.push_back(r * k / q);
  }
  std::ostringstream os;
  os << k << " folds of whole optical axes (" << q << " axes, consecutive plan axes together); "
     << "each held-out axis scored by the straightness of its predicted points (its own line "
        "and depth offset fitted to them)";
  *rule = os.str();
  return fold;
}

}  // namespace twin::discovery
