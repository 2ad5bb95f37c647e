// TwinCell::RequestStop and TwinCell::SetRealtime (a served twin: the watchdog stops motion; the
// simulation paced to wall-clock time).
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "sim/cell/twin_cell.h"
#include "tests/sim/test_twin_specs.h"

namespace twin {
namespace {

using testing::DemoTwinSpec;

double Seconds(std::chrono::steady_clock::duration d) {
  return std::chrono::duration<double>(d).count();
}

// A 1 rad move of joint 1 at the default 1 rad/s: 1 s of motion.
JointVector Target(TwinCell& cell) {
  JointVector q = cell.ReadEncoders(0);
  q(0) += 1.0;
  return q;
}

TEST(TwinCellStop, RealtimeMoveTakesItsSimulatedTimeInWallTime) {
  TwinCell cell(DemoTwinSpec());
  cell.SetRealtime(true);
  const auto t0 = std::chrono::steady_clock::now();
  const MoveResult r = cell.MoveTo(0, Target(cell));
  const double wall = Seconds(std::chrono::steady_clock::now() - t0);
  ASSERT_EQ(r.status, MoveStatus::kSettled) << r.reason;
  EXPECT_GE(r.duration_s, 1.0);
  // Never faster than simulated time; at most 1 s slower (2 shared cores).
  EXPECT_GE(wall, r.duration_s);
  EXPECT_LE(wall, r.duration_s + 1.0);
}

TEST(TwinCellStop, RequestStopEndsTheMoveInProgress) {
  TwinCell cell(DemoTwinSpec());
  cell.SetRealtime(true);
  const JointVector start = cell.ReadEncoders(0);
  const JointVector target = Target(cell);
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    cell.RequestStop();
  });
  const auto t0 = std::chrono::steady_clock::now();
  const MoveResult r = cell.MoveTo(0, target);
  const double wall = Seconds(std::chrono::steady_clock::now() - t0);
  stopper.join();
  EXPECT_EQ(r.status, MoveStatus::kNotSettled);
  EXPECT_EQ(r.reason, "stopped");
  EXPECT_LT(wall, 0.8);  // stopped at 0.3 s of a 1 s move
  // Where it stopped: between start and target, and it holds there.
  const JointVector stopped = cell.ReadEncoders(0);
  EXPECT_GT(stopped(0) - start(0), 0.1);
  EXPECT_LT(stopped(0) - start(0), 0.8);
  // The request cleared: the next move settles at the target.
  const MoveResult again = cell.MoveTo(0, target);
  EXPECT_EQ(again.status, MoveStatus::kSettled) << again.reason;
  EXPECT_NEAR(cell.ReadEncoders(0)(0), target(0), 1e-12);
}

// A request while nothing moves stops nothing, and the default (no pacing) is the same
// simulation: two twins, the same moves, bit-identical encoders and clock.
TEST(TwinCellStop, StopBetweenMovesChangesNothing) {
  TwinCell a(DemoTwinSpec()), b(DemoTwinSpec());
  a.RequestStop();
  const MoveResult ra = a.MoveTo(0, Target(a));
  const MoveResult rb = b.MoveTo(0, Target(b));
  EXPECT_EQ(ra.status, MoveStatus::kSettled) << ra.reason;
  EXPECT_EQ(ra.duration_s, rb.duration_s);
  EXPECT_EQ(a.ClockSeconds(), b.ClockSeconds());
  EXPECT_EQ(a.Truth().q_link[0], b.Truth().q_link[0]);
}

}  // namespace
}  // namespace twin
