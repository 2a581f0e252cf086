// Angles.
#pragma once

#include <cmath>
#include <numbers>

namespace odotune::core {

// a_rad wrapped to (−π, π] [rad] (std::remainder, exact).
inline double wrap_angle(double a_rad) {
  constexpr double kPi = std::numbers::pi;
  double w = std::remainder(a_rad, 2.0 * kPi);  // [−π, π]
  if (w <= -kPi) w += 2.0 * kPi;
  return w;
}

}  // namespace odotune::core
