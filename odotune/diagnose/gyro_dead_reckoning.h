// Dead reckoning with the heading from the GYRO and the distance from the
// WHEELS over one window of window_replay.h, and the closed-form rigid
// alignment of a prediction onto a window's position fixes: the model of
// gyro_fixes_check.h (whose header comment gives the equations and why).
// Templated on the scalar type (Ceres Jets). No I/O; SI units.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include <odotune/core/planar_motion.h>
#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/effect_model.h>
#include <odotune/diagnose/window_replay.h>

namespace odotune::diagnose {

// Nominal wheel distance and gyro heading at the odometry nodes
// (DiagInput::odo_t_s).
struct GyroDrSeries {
  std::vector<double> t;  // node times [s]
  std::vector<double> s;  // cumulative nominal distance, mean of the two rim travels [m]
  std::vector<double> g;  // cumulative gyro integral G(t_k) [rad] (NaN outside the gyro's span)
};

// Parameters of one replay: gyro scale s, gyro bias b [rad/s] (the gyro
// reads s*w + b) and a common scale q of the wheel distance.
template <typename T>
struct GyroParams {
  T s, b, q;
};

// Positions predicted at the reference samples of w (times ref_t), from
// `anchor` at node w.node_begin: heading theta(t_k) = anchor.th + (G(t_k) -
// G(t_a) - b*(t_k - t_a))/s (t_a the anchor time), distance q*(S(t_{k+1}) -
// S(t_k)) per interval, the arc update of effect_model.h's advance(); a
// sample between two nodes is interpolated linearly (as replay_window).
// px/py hold w.ref_end - w.ref_begin values.
template <typename T>
void gyro_replay(const GyroDrSeries& d, const Window& w, const std::vector<double>& ref_t,
                 const GyroParams<T>& gp, const Pose<T>& anchor, T* px, T* py) {
  using std::cos;
  using std::sin;
  const std::size_t k0 = w.node_begin;
  const double g0 = d.g[k0], t0 = d.t[k0];
  const T inv_s = 1.0 / gp.s;
  T x = anchor.x, y = anchor.y, th = anchor.th;
  std::size_t r = w.ref_begin;
  while (r < w.ref_end && ref_t[r] <= d.t[k0]) {
    px[r - w.ref_begin] = x;
    py[r - w.ref_begin] = y;
    ++r;
  }
  for (std::size_t k = k0; k < w.node_end && r < w.ref_end; ++k) {
    // Heading at node k+1 in closed form (no accumulated rounding).
    const T th1 = anchor.th + (d.g[k + 1] - g0 - gp.b * (d.t[k + 1] - t0)) * inv_s;
    const T half = 0.5 * (th1 - th);
    const T chord = gp.q * (d.s[k + 1] - d.s[k]) * core::sinc(half);
    const T mid = th + half;
    const T x1 = x + chord * cos(mid), y1 = y + chord * sin(mid);
    const double h = d.t[k + 1] - d.t[k];
    while (r < w.ref_end && ref_t[r] <= d.t[k + 1]) {
      const double f = (ref_t[r] - d.t[k]) / h;
      px[r - w.ref_begin] = x + f * (x1 - x);
      py[r - w.ref_begin] = y + f * (y1 - y);
      ++r;
    }
    x = x1;
    y = y1;
    th = th1;
  }
  for (; r < w.ref_end; ++r) {
    px[r - w.ref_begin] = x;
    py[r - w.ref_begin] = y;
  }
}

// `a` composed with the rigid motion (rotation phi about the origin, then a
// translation) that maps the predictions (px, py) of window w onto its
// reference positions in least squares (Kabsch/Umeyama without scale).
inline Pose<double> align_rigid(const Pose<double>& a, const std::vector<double>& px,
                                const std::vector<double>& py, const DiagInput& in, const Window& w) {
  const std::size_t b = w.ref_begin;
  const core::RigidMotion2d m = core::fit_rigid_2d(
      px.size(), [&](std::size_t i) { return px[i]; }, [&](std::size_t i) { return py[i]; },
      [&](std::size_t i) { return in.ref_x_m[b + i]; }, [&](std::size_t i) { return in.ref_y_m[b + i]; });
  Pose<double> out = a;
  m.apply(&out.x, &out.y, &out.th);
  return out;
}

}  // namespace odotune::diagnose
