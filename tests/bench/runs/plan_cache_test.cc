#include "bench/runs/plan_cache.h"
#include "bench/report/plan_file.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include <gtest/gtest.h>

namespace twin {
namespace {

PosePlanResult SomePlan() {
  PosePlanResult p;
  p.status = PosePlannerStatus::kSuccess;
  p.best_fitness = 1.0 / 3.0;  // not a short decimal: the round trip must be exact
  p.best_run = 1;
  p.evaluations = 1234;
  p.rejections.c3_visibility = 5;
  p.rejections.active_ik = 2;
  p.fitness_history = {{std::numeric_limits<double>::infinity(), 0.7, 0.1 / 3.0}, {0.9, 0.2}};
  p.run_fitness = {0.1 / 3.0, 0.2};
  p.run_predicted_error = {1.3e-4 / 3.0, std::numeric_limits<double>::infinity()};
  p.run_predicted_similarity_error = {0.9e-4 / 7.0, std::numeric_limits<double>::infinity()};
  for (int k = 0; k < 2; ++k) {
    PlannedAxis a;
    a.camera_origin = Vector3(0.1 * k + 1e-17, std::sqrt(2.0), -std::acos(-1.0));
    a.direction = Vector3(1, 2, 3).normalized();
    a.q_active = JointVector::LinSpaced(6, -1.0 / 7.0, 2.0 / 3.0);
    for (int i = 0; i < 3; ++i) {
      a.q_passive.push_back(JointVector::LinSpaced(6, 0.1 * i, std::exp(1.0)));
      a.distances.push_back(0.3 + 0.02 * i);
    }
    p.axes.push_back(a);
  }
  return p;
}

void ExpectBitEqual(const PosePlanResult& a, const PosePlanResult& b) {
  ASSERT_EQ(a.axes.size(), b.axes.size());
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.best_run, b.best_run);
  EXPECT_EQ(a.evaluations, b.evaluations);
  EXPECT_EQ(a.rejections.c3_visibility, b.rejections.c3_visibility);
  EXPECT_EQ(a.rejections.active_ik, b.rejections.active_ik);
  EXPECT_EQ(std::memcmp(&a.best_fitness, &b.best_fitness, sizeof(double)), 0);
  EXPECT_EQ(a.fitness_history, b.fitness_history);  // exact, infinity included
  EXPECT_EQ(a.run_fitness, b.run_fitness);
  EXPECT_EQ(a.run_predicted_error, b.run_predicted_error);
  EXPECT_EQ(a.run_predicted_similarity_error, b.run_predicted_similarity_error);
  for (std::size_t k = 0; k < a.axes.size(); ++k) {
    EXPECT_EQ(a.axes[k].camera_origin, b.axes[k].camera_origin);
    EXPECT_EQ(a.axes[k].direction, b.axes[k].direction);
    EXPECT_EQ(a.axes[k].q_active, b.axes[k].q_active);
    EXPECT_EQ(a.axes[k].q_passive, b.axes[k].q_passive);
    EXPECT_EQ(a.axes[k].distances, b.axes[k].distances);
  }
}

PlanInputs Inputs(std::uint64_t seed) {
  PlanInputs in;
  in.options.seed = seed;
  return in;
}

std::string TempFolder(const std::string& name) {
  const std::string d = ::testing::TempDir() + "/plan_cache_" + name;
  std::filesystem::remove_all(d);
  return d;
}

TEST(PlanCacheTest, JsonRoundTripIsBitExact) {
  const PosePlanResult p = SomePlan();
  ExpectBitEqual(p, PlanFromJson(nlohmann::json::parse(PlanToJson(p).dump()), "test"));
}

TEST(PlanCacheTest, MissThenStoreThenHitAcrossStores) {
  const std::string dir = TempFolder("hit");
  {
    FilePlanStore store(dir);
    EXPECT_FALSE(store.Find(Inputs(1)).has_value());
    store.Store(Inputs(1), SomePlan());
    EXPECT_EQ(store.misses(), 1);
  }
  FilePlanStore other(dir);  // another process' store on the same folder
  const std::optional<PosePlanResult> got = other.Find(Inputs(1));
  ASSERT_TRUE(got.has_value());
  ExpectBitEqual(SomePlan(), *got);
  EXPECT_EQ(other.hits(), 1);
  EXPECT_FALSE(other.Find(Inputs(2)).has_value());  // other inputs: another plan
  other.Abandon(Inputs(2));
}

TEST(PlanCacheTest, ACorruptFileIsAMissNotAnError) {
  const std::string dir = TempFolder("corrupt");
  FilePlanStore store(dir);
  // The right inputs but no plan in it (a file from a broken version, say).
  std::ofstream(store.PathFor(Inputs(3)))
      << nlohmann::json{{"inputs", PlanInputsText(Inputs(3))}, {"plan", 5}}.dump();
  EXPECT_FALSE(store.Find(Inputs(3)).has_value());
  store.Store(Inputs(3), SomePlan());
  EXPECT_TRUE(FilePlanStore(dir).Find(Inputs(3)).has_value());
}

TEST(PlanCacheTest, ASecondProcessWaitsForThePlanInsteadOfPlanningAgain) {
  const std::string dir = TempFolder("wait");
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {  // the first trial: misses, "plans" for 0.3 s, stores
    FilePlanStore store(dir);
    const bool miss = !store.Find(Inputs(4)).has_value();
    const char c = miss ? 'm' : 'h';
    if (write(ready[1], &c, 1) != 1) _exit(3);
    usleep(300000);
    store.Store(Inputs(4), SomePlan());
    _exit(0);
  }
  char c = 0;
  ASSERT_EQ(read(ready[0], &c, 1), 1);
  EXPECT_EQ(c, 'm');
  // The child holds the lock now: Find blocks until it stored, then returns its plan. Without
  // the lock this Find would miss (the file is written 0.3 s later).
  FilePlanStore store(dir);
  const std::optional<PosePlanResult> got = store.Find(Inputs(4));
  int status = 0;
  waitpid(child, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  ASSERT_TRUE(got.has_value());
  ExpectBitEqual(SomePlan(), *got);
  close(ready[0]);
  close(ready[1]);
}

}  // namespace
}  // namespace twin
