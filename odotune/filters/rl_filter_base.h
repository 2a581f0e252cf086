// What robot_localization's EKF and UKF share (its FilterBase,
// filter_base.cpp, and the measurement handling both corrections repeat):
// the members a measurement fuses, its covariance as the filters repair it,
// and the first measurement's initialisation. Used by odotune/filters/rl_ekf.cpp and
// odotune/filters/rl_ukf.cpp.
#pragma once

#include <cstdint>

#include <odotune/filters/rl_ekf.h>

namespace odotune::filters::rl::detail {

// The members a measurement fuses: its mask less non-finite values (both
// filters leave nan and inf out). Writes their indices to idx[0 … n) and
// returns n.
int fused_members(const Measurement& m, int* idx);

// A measured variance as both filters take it: a negative one by its
// magnitude, one below 1e-9 raised to it.
double positive_variance(double r);

// z[0 … n) and R (n × n, column-major) of the members idx[0 … n), R's
// diagonal through positive_variance.
void gather(const Measurement& m, int n, const int* idx, double* z, double* R);

// (A + Aᵀ)/2.
Cov symmetric(const Cov& a);

// FilterBase::processMeasurement's first measurement: the fused members and
// their covariance block (its symmetric part) taken from it.
void initialise(const Measurement& m, State& x, Cov& P);

// FilterBase::processMeasurement's clock, for every filter here: the first
// measurement (at t_ns) initialises, init() giving the result; a later one
// predicts over the time since the last when it is positive [s], then
// corrects; the last measurement time moves only forward.
template <class Init, class Predict, class Correct>
auto process_measurement(bool& initialized, std::int64_t& last_ns, std::int64_t t_ns, Init init,
                         Predict predict, Correct correct) -> decltype(correct()) {
  if (!initialized) {
    initialized = true;
    last_ns = t_ns;
    return init();
  }
  const std::int64_t delta = t_ns - last_ns;
  if (delta > 0) predict(static_cast<double>(delta) * 1e-9);
  const auto accepted = correct();
  if (delta >= 0) last_ns = t_ns;
  return accepted;
}

// The node's prediction to t_ns without a measurement; sets the last time.
template <class Predict>
void predict_to(std::int64_t& last_ns, std::int64_t t_ns, Predict predict) {
  const std::int64_t delta = t_ns - last_ns;
  if (delta > 0) predict(static_cast<double>(delta) * 1e-9);
  last_ns = t_ns;
}

}  // namespace odotune::filters::rl::detail
