#include "bench/report/plan_file.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

namespace twin {
namespace {

TEST(PlanFileTest, AFileIsReadBackOnlyForItsOwnInputs) {
  const std::string path = ::testing::TempDir() + "/plan_file_test.json";
  std::filesystem::remove(path);
  EXPECT_FALSE(ReadPlanFile(path, "inputs a"));  // missing: a miss
  PosePlanResult plan;
  plan.status = PosePlannerStatus::kNoFeasiblePoses;
  plan.reason = "no pose";
  plan.best_fitness = 0.1;  // not exact in binary: the hex float keeps every bit
  plan.evaluations = 12;
  std::ofstream(path) << PlanFileText("inputs a", plan);
  const std::optional<PosePlanResult> read = ReadPlanFile(path, "inputs a");
  ASSERT_TRUE(read);
  EXPECT_EQ(read->status, PosePlannerStatus::kNoFeasiblePoses);
  EXPECT_EQ(read->reason, "no pose");
  EXPECT_EQ(read->best_fitness, 0.1);
  EXPECT_EQ(read->evaluations, 12);
  EXPECT_FALSE(ReadPlanFile(path, "inputs b"));  // another input with the same hash
  std::ofstream(path) << "{\"inputs\": \"inputs a\", \"plan\": {\"status\": \"?\"}}\n";
  EXPECT_FALSE(ReadPlanFile(path, "inputs a"));  // malformed: a miss, never an error
}

}  // namespace
}  // namespace twin
