// A track's body velocities v_cmd, w_cmd as functions of time, each sample
// held until the next one (zero-order hold: a command stands until it is
// replaced, and a reported twist, as Lost in the Woods' 10 Hz odometry shows
// against its ground truth, describes the interval after its stamp), and
// their integrals, so that the mean over any interval, optionally delayed,
// is exact.
#pragma once

#include <array>
#include <vector>

#include <odotune/tracks/track.h>

namespace odotune::tracks {

class BodyVelocityIntegral {
 public:
  // The rows with both v_cmd and w_cmd, in time order.
  explicit BodyVelocityIntegral(const Track& track);

  // Sample times [s]; the last one closes the last interval and holds
  // nothing beyond it.
  const std::vector<double>& t() const { return t_; }
  std::size_t size() const { return t_.size(); }

  // (∫v dt [m], ∫w dt [rad]) from the first sample to t_s, clamped to
  // [t().front(), t().back()] (0 before, the total after).
  std::array<double, 2> at(double t_s) const;
  // The mean (v [m/s], w [rad/s]) over (t0_s − delay_s, t1_s − delay_s];
  // requires t1_s > t0_s.
  std::array<double, 2> mean(double t0_s, double t1_s, double delay_s = 0.0) const;

 private:
  std::vector<double> t_, v_, w_, cum_v_, cum_w_;
};

}  // namespace odotune::tracks
