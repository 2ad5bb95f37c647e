#include "calib/common/cpus.h"

#include <sched.h>

#include <gtest/gtest.h>

namespace twin {
namespace {

// The count follows the affinity mask (what a Slurm allocation or a study's trial slot sets),
// not the machine's CPUs: confined to one CPU, the thread sees exactly that one.
TEST(UsableCpus, FollowTheAffinityMask) {
  cpu_set_t before;
  CPU_ZERO(&before);
  ASSERT_EQ(sched_getaffinity(0, sizeof(before), &before), 0);
  const std::vector<int> all = UsableCpuList();
  ASSERT_EQ(static_cast<int>(all.size()), CPU_COUNT(&before));
  ASSERT_EQ(UsableCpuCount(), CPU_COUNT(&before));
  for (std::size_t i = 1; i < all.size(); ++i) EXPECT_LT(all[i - 1], all[i]);

  const int last = all.back();
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(last, &one);
  ASSERT_EQ(sched_setaffinity(0, sizeof(one), &one), 0);
  const std::vector<int> confined = UsableCpuList();
  const int count = UsableCpuCount();
  ASSERT_EQ(sched_setaffinity(0, sizeof(before), &before), 0);  // restore before asserting
  EXPECT_EQ(confined, std::vector<int>{last});
  EXPECT_EQ(count, 1);
}

}  // namespace
}  // namespace twin
