// seconds_since: the wall time since a steady-clock instant [s], for the
// timings a run reports.
#pragma once

#include <chrono>

namespace odotune::core {

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace odotune::core
