// Wall-clock timing for stage times and budgets, defined once. Header-only, so the runtime uses
// it too.
#pragma once

#include <chrono>

namespace afterglow {

using Clock = std::chrono::steady_clock;

// Seconds since t.
inline double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}
// Milliseconds since t.
inline double millisecondsSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

}  // namespace afterglow
