#include <odotune/filters/rl_control.h>

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include <odotune/core/why.h>

namespace odotune::filters::rl {

bool RlControlParams::IsValid(std::string* why) const {
  if (timeout_ns < 0) return core::invalid(why, fmt::format("control timeout {} ns < 0", timeout_ns));
  const std::pair<const char*, const ControlVector*> lists[] = {{"acceleration_limits", &acceleration_limits},
                                                                {"acceleration_gains", &acceleration_gains},
                                                                {"deceleration_limits", &deceleration_limits},
                                                                {"deceleration_gains", &deceleration_gains}};
  for (const auto& [name, list] : lists) {
    for (int i = 0; i < kControlSize; ++i) {
      const double v = (*list)[i];
      if (!std::isfinite(v) || v < 0.0)
        return core::invalid(why, fmt::format("{}[{}] = {}: expected a finite value ≥ 0", name, i, v));
    }
  }
  return true;
}

double control_acceleration(double v, double u, double acceleration_limit, double acceleration_gain,
                            double deceleration_limit, double deceleration_gain) {
  const double error = u - v;
  const bool same_sign = std::abs(error) <= std::abs(u) + 0.01;
  const double set_point = same_sign ? u : 0.0;
  const bool decelerating = std::abs(set_point) < std::abs(v);
  const double limit = decelerating ? deceleration_limit : acceleration_limit;
  const double gain = decelerating ? deceleration_gain : acceleration_gain;
  return std::min(std::max(gain * error, -limit), limit);
}

ControlVector control_accelerations(const RlControlParams& p, const Command& c, const ControlVector& v,
                                    std::int64_t reference_ns) {
  const std::int64_t age = reference_ns - c.time_ns;
  const bool timed_out = (p.timeout_rule == ControlTimeout::absolute ? std::abs(age) : age) >= p.timeout_ns;
  ControlVector a{};
  for (int i = 0; i < kControlSize; ++i) {
    if (!p.update[i]) continue;
    a[i] = control_acceleration(v[i], timed_out ? 0.0 : c.u[i], p.acceleration_limits[i],
                                p.acceleration_gains[i], p.deceleration_limits[i], p.deceleration_gains[i]);
  }
  return a;
}

}  // namespace odotune::filters::rl
