// Planar dead reckoning, written once for every module and for any scalar
// type (double, or ceres::Jet for the fits that differentiate through it):
// the midpoint step of the track format's differential-drive kinematics and
// the exact arc step for constant body velocities. Distances [m], angles [rad].
#pragma once

#include <cmath>
#include <cstddef>

namespace odotune::core {

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

// The rigid motion (rotation phi about the origin, then translation (tx, ty))
// that maps the points p onto the points q in least squares (2-D Kabsch, no
// scale); spread_m2 = Σ|q_i − q̄|². apply() maps a pose [m, m, rad].
struct RigidMotion2d {
  double phi = 0.0, tx = 0.0, ty = 0.0;
  double spread_m2 = 0.0;

  void apply(double* x, double* y, double* theta) const {
    const double cp = std::cos(phi), sp = std::sin(phi);
    const double x0 = *x;
    *x = cp * x0 - sp * *y + tx;
    *y = sp * x0 + cp * *y + ty;
    *theta += phi;
  }
};

// px(i), py(i) and qx(i), qy(i) give the coordinates [m] of point i of p
// and of q, for i < n, n > 0.
template <class Px, class Py, class Qx, class Qy>
RigidMotion2d fit_rigid_2d(std::size_t n, Px&& px, Py&& py, Qx&& qx, Qy&& qy) {
  double mx = 0, my = 0, fx = 0, fy = 0;
  for (std::size_t i = 0; i < n; ++i) {
    mx += px(i), my += py(i);
    fx += qx(i), fy += qy(i);
  }
  const auto nn = static_cast<double>(n);
  mx /= nn, my /= nn, fx /= nn, fy /= nn;
  double c = 0, s = 0;
  RigidMotion2d m;
  for (std::size_t i = 0; i < n; ++i) {
    const double ax = px(i) - mx, ay = py(i) - my;
    const double bx = qx(i) - fx, by = qy(i) - fy;
    c += ax * bx + ay * by;
    s += ax * by - ay * bx;
    m.spread_m2 += bx * bx + by * by;
  }
  m.phi = (c == 0.0 && s == 0.0) ? 0.0 : std::atan2(s, c);
  const double cp = std::cos(m.phi), sp = std::sin(m.phi);
  m.tx = fx - (cp * mx - sp * my);
  m.ty = fy - (sp * mx + cp * my);
  return m;
}

}  // namespace odotune::core
