// Wall time for the reports' *_ms fields and the stages' timings.
#pragma once

#include <chrono>

namespace meshmend {

using Clock = std::chrono::steady_clock;

// Milliseconds since `start`.
inline double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace meshmend
