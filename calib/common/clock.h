// Wall-clock timing of stages and runs (the steady clock; timing figures of reports and
// benchmarks).
#pragma once

#include <chrono>

namespace twin {

using Clock = std::chrono::steady_clock;

/// Seconds elapsed since `since` [s].
inline double SecondsSince(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

}  // namespace twin
