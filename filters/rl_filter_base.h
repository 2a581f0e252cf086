// What robot_localization's EKF and UKF share (its FilterBase,
// filter_base.cpp, and the measurement handling both corrections repeat):
// the members a measurement fuses, its covariance as the filters repair it,
// and the first measurement's initialisation. Used by filters/rl_ekf.cpp and
// filters/rl_ukf.cpp.
#pragma once

#include "filters/rl_ekf.h"

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

}  // namespace odotune::filters::rl::detail
