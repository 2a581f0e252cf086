// Planar dead reckoning, written once for every module and for any scalar
// type (double, or ceres::Jet for the fits that differentiate through it):
// the midpoint step of the track format's differential-drive kinematics and
// the exact arc step for constant body velocities. Distances [m], angles [rad].
#pragma once

#include <cmath>

namespace odotune {

// sin(x)/x, accurate near 0 (the series 1 − x²/6 below |x| = 1e-4, where
// sin(x)/x loses digits).
template <typename T>
T sinc(const T& x) {
  using std::abs;
  using std::sin;
  return abs(x) < T(1e-4) ? T(1.0) - x * x / 6.0 : sin(x) / x;
}

// One midpoint step of a differential drive from the distances its wheels
// travelled (../shared/specs/track-format.md):
//   d = (l + r)/2,  Δθ = (r − l)/D,  θm = θ + Δθ/2,
//   x += d·cos θm,  y += d·sin θm,  θ += Δθ.
// filters::diff_drive_step is this step with its Jacobians; on doubles both
// give the same pose to the bit (tests/filters/test_ekf.cpp).
template <typename T>
void midpoint_advance(T* x, T* y, T* theta, const T& left_m, const T& right_m, const T& wheel_base_m) {
  using std::cos;
  using std::sin;
  const T d = 0.5 * (left_m + right_m);
  const T dtheta = (right_m - left_m) / wheel_base_m;
  const T theta_m = *theta + 0.5 * dtheta;
  *x = *x + d * cos(theta_m);
  *y = *y + d * sin(theta_m);
  *theta = *theta + dtheta;
}

// One arc step, exact when the forward and lateral body velocities and the
// turn rate are constant over the step:
//   θm = θ + half,  x += scale·(fwd·cos θm − lat·sin θm),
//   y += scale·(fwd·sin θm + lat·cos θm),  θ += dtheta,
// with half = dtheta/2 and scale = sinc(half) when fwd and lat are distances
// over the step, sinc(half)·h when they are velocities over a step of h
// seconds. The caller passes half and scale as it computed them, so that
// every caller keeps its own rounding.
template <typename T>
void arc_advance(T* x, T* y, T* theta, const T& half, const T& scale, const T& fwd, const T& lat,
                 const T& dtheta) {
  using std::cos;
  using std::sin;
  const T theta_m = *theta + half;
  const T c = cos(theta_m), s = sin(theta_m);
  *x += scale * (fwd * c - lat * s);
  *y += scale * (fwd * s + lat * c);
  *theta += dtheta;
}

}  // namespace odotune
