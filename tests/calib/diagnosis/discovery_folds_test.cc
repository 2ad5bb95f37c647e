#include "calib/diagnosis/discovery_folds.h"

#include <algorithm>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "calib/common/errors.h"

namespace twin::discovery {
namespace {

TEST(DiscoveryFolds, RandomFoldsDealEveryUnitToOneFoldInNearlyEqualShares) {
  const std::vector<int> fold = RandomFolds(23, 5, 7);
  ASSERT_EQ(fold.size(), 23u);
  std::vector<int> count(5, 0);
  for (int f : fold) {
    ASSERT_GE(f, 0);
    ASSERT_LT(f, 5);
    ++count[f];
  }
  // 23 = 4 * 5 + 3: three folds of 5, two of 4.
  std::sort(count.begin(), count.end());
  EXPECT_EQ(count, (std::vector<int>{4, 4, 5, 5, 5}));
  // The seed decides the order: the same seed the same folds, another seed others.
  EXPECT_EQ(RandomFolds(23, 5, 7), fold);
  EXPECT_NE(RandomFolds(23, 5, 8), fold);
}

TrackerPoint At(double x, double y, double z) {
  TrackerPoint p;
  p.p_T = Vector3(x, y, z);
  return p;
}

TEST(DiscoveryFolds, RegionFoldsAreTheSeparatedClustersOfThePoints) {
  // Three tight clusters 1 m apart (4, 3 and 2 points): k-means with k = 3 finds exactly them.
  const std::vector<TrackerPoint> points{
      At(0, 0, 0),       At(0.01, 0, 0), At(0, 0.01, 0), At(0, 0, 0.01),  // cluster A
      At(1, 0, 0),       At(1.01, 0, 0), At(1, 0.01, 0),                  // cluster B
      At(0, 1, 0),       At(0.01, 1, 0)};                                 // cluster C
  std::string rule;
  const std::vector<int> fold = RegionFolds(points, 3, &rule);
  ASSERT_EQ(fold.size(), points.size());
  for (int i : {1, 2, 3}) EXPECT_EQ(fold[i], fold[0]);
  for (int i : {5, 6}) EXPECT_EQ(fold[i], fold[4]);
  EXPECT_EQ(fold[8], fold[7]);
  EXPECT_NE(fold[0], fold[4]);
  EXPECT_NE(fold[0], fold[7]);
  EXPECT_NE(fold[4], fold[7]);
  EXPECT_NE(rule.find("3 workspace blocks"), std::string::npos) << rule;
  EXPECT_THROW(RegionFolds(points, 0, &rule), PreconditionError);
}

TEST(DiscoveryFolds, AxisFoldsKeepEachAxisWholeAndConsecutiveAxesTogether) {
  // Axes 0, 2, 5, 7 (gaps: plan axes), two samples each, out of order; 2 folds: ranks 0 and 1
  // in fold 0, ranks 2 and 3 in fold 1 (r k / q).
  const std::vector<int> sample_axes{5, 0, 2, 7, 0, 5, 2, 7};
  std::string rule;
  const std::vector<int> fold = AxisFolds(sample_axes, 2, &rule);
  EXPECT_EQ(fold, (std::vector<int>{1, 0, 0, 1, 0, 1, 0, 1}));
  EXPECT_NE(rule.find("4 axes"), std::string::npos) << rule;
  // As many folds as axes: one axis a fold, in the order of the axes.
  EXPECT_EQ(AxisFolds(sample_axes, 4, &rule), (std::vector<int>{2, 0, 1, 3, 0, 2, 1, 3}));
  EXPECT_THROW(AxisFolds(sample_axes, 5, &rule), PreconditionError);
}

}  // namespace
}  // namespace twin::discovery
