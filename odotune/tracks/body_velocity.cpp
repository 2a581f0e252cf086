#include <odotune/tracks/body_velocity.h>

#include <algorithm>

namespace odotune::tracks {

BodyVelocityIntegral::BodyVelocityIntegral(const Track& track) {
  for (std::size_t i = 0; i < track.size(); ++i) {
    if (!track.at(Col::v_cmd, i) || !track.at(Col::w_cmd, i)) continue;
    const double ti = track.t()[i];
    if (t_.empty()) {
      cum_v_.push_back(0.0);
      cum_w_.push_back(0.0);
    } else {
      const double dt = ti - t_.back();
      cum_v_.push_back(cum_v_.back() + v_.back() * dt);
      cum_w_.push_back(cum_w_.back() + w_.back() * dt);
    }
    t_.push_back(ti);
    v_.push_back(track.col(Col::v_cmd)[i]);
    w_.push_back(track.col(Col::w_cmd)[i]);
  }
}

std::array<double, 2> BodyVelocityIntegral::at(double t_s) const {
  if (t_.empty() || t_s <= t_.front()) return {0.0, 0.0};
  if (t_s >= t_.back()) return {cum_v_.back(), cum_w_.back()};
  const auto i = static_cast<std::size_t>(std::upper_bound(t_.begin(), t_.end(), t_s) - t_.begin()) - 1;
  const double dt = t_s - t_[i];
  return {cum_v_[i] + v_[i] * dt, cum_w_[i] + w_[i] * dt};
}

std::array<double, 2> BodyVelocityIntegral::mean(double t0_s, double t1_s, double delay_s) const {
  const auto a = at(t0_s - delay_s), b = at(t1_s - delay_s);
  const double dt = t1_s - t0_s;
  return {(b[0] - a[0]) / dt, (b[1] - a[1]) / dt};
}

}  // namespace odotune::tracks
