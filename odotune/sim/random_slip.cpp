#include <odotune/sim/random_slip.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/counter_rng.h>
#include <odotune/core/why.h>
#include <odotune/sim/slip_episodes.h>

namespace odotune::sim {

namespace {

bool finite_nonneg(double x) { return std::isfinite(x) && x >= 0.0; }

// True when |v| ≥ min_speed at every 0.05 s of [t0, t1].
bool moving_throughout(const MotionProfile& p, double t0, double t1, double min_speed) {
  for (double t = t0;; t = std::min(t1, t + 0.05)) {
    if (std::abs(p.at(t).v_m_s) < min_speed) return false;
    if (t >= t1) return true;
  }
}

}  // namespace

bool RandomSlipOptions::IsValid(std::string* why) const {
  if (!finite_nonneg(first_s))
    return core::invalid(why, fmt::format("first_s = {}: expected a finite value >= 0", first_s));
  if (!finite_nonneg(end_margin_s))
    return core::invalid(why, fmt::format("end_margin_s = {}: expected a finite value >= 0", end_margin_s));
  if (!(min_duration_s >= 0.5 && max_duration_s >= min_duration_s && std::isfinite(max_duration_s)))
    return core::invalid(
        why, fmt::format("min_duration_s = {}, max_duration_s = {}: expected 0.5 <= min <= max, finite",
                         min_duration_s, max_duration_s));
  if (!(min_gap_s >= 0.0 && max_gap_s >= min_gap_s && std::isfinite(max_gap_s)))
    return core::invalid(why, fmt::format("min_gap_s = {}, max_gap_s = {}: expected 0 <= min <= max, finite",
                                          min_gap_s, max_gap_s));
  if (!(min_strength > 0.0 && max_strength >= min_strength && max_strength <= 0.9))
    return core::invalid(why,
                         fmt::format("min_strength = {}, max_strength = {}: expected 0 < min <= max <= 0.9",
                                     min_strength, max_strength));
  if (!finite_nonneg(min_speed_m_s))
    return core::invalid(why, fmt::format("min_speed_m_s = {}: expected a finite value >= 0", min_speed_m_s));
  if (!std::isfinite(hold_brake_per_s_nm) || !std::isfinite(hold_brake_offset_nm) ||
      hold_brake_per_s_nm * min_strength + hold_brake_offset_nm < 0.0 ||
      hold_brake_per_s_nm * max_strength + hold_brake_offset_nm < 0.0)
    return core::invalid(
        why, fmt::format("hold_brake_per_s_nm = {}, hold_brake_offset_nm = {}: expected finite values giving a "
                         "brake >= 0 N*m over the strength range",
                         hold_brake_per_s_nm, hold_brake_offset_nm));
  if (!finite_nonneg(ramp_per_strength_s))
    return core::invalid(why, fmt::format("ramp_per_strength_s = {}: expected a finite value >= 0",
                                          ramp_per_strength_s));
  return true;
}

std::vector<SlipEpisode> random_slip_episodes(const MotionProfile& profile, std::uint64_t seed,
                                              const RandomSlipOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument("random slip episodes: " + why);
  std::uint64_t draw = 0;
  const auto uniform = [&](double lo, double hi) {
    return lo + (hi - lo) * core::counter_uniform01(seed, draw++, 0, 0, 0x51ED);
  };
  const double end = profile.duration_s() - o.end_margin_s;
  std::vector<SlipEpisode> out;
  // Try a start, then slide it forward in 0.25 s steps until the episode lies
  // in a moving stretch; the draws per episode are fixed, so the layout does
  // not depend on how far a start had to slide.
  for (double t = o.first_s + uniform(0.0, o.max_gap_s - o.min_gap_s);;) {
    SlipEpisode e;
    const double d = uniform(o.min_duration_s, o.max_duration_s);
    e.kind = uniform(0.0, 1.0) < 0.5 ? SlipEpisode::Kind::spin : SlipEpisode::Kind::hold;
    e.wheel = uniform(0.0, 1.0) < 0.5 ? SlipEpisode::Wheel::left : SlipEpisode::Wheel::right;
    e.s = uniform(o.min_strength, o.max_strength);
    const double gap = uniform(o.min_gap_s, o.max_gap_s);
    e.ramp_s = std::min(0.2 + o.ramp_per_strength_s * std::max(0.0, e.s - 0.5), 0.4 * d);
    if (e.kind == SlipEpisode::Kind::hold)
      e.brake_nm = std::max(0.0, o.hold_brake_per_s_nm * e.s + o.hold_brake_offset_nm);
    while (t + d <= end && !moving_throughout(profile, t, t + d, o.min_speed_m_s)) t += 0.25;
    if (t + d > end) break;
    e.t0_s = t;
    e.t1_s = t + d;
    out.push_back(e);
    t += d + gap;
  }
  if (!validate_slip_episodes(out, &why))  // a bug here, not bad input
    throw std::logic_error("random slip episodes: " + why);
  return out;
}

}  // namespace odotune::sim
