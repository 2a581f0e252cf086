// A planar pose series (typically a track's ground truth) with linear
// interpolation and body velocities by central differences: what the
// odometry calibration (calibration_input.h, calibration_run.h) derives
// reference velocities from.
#pragma once

#include <optional>
#include <vector>

#include <odotune/core/angles.h>
#include <odotune/filters/odometry_params.h>

namespace odotune::objectives {

using PlanarPose = filters::PlanarPose;  // one pose type for filters and objectives

// Contract: t strictly increasing [s]; x, y [m] and theta [rad, unwrapped]
// finite and as long as t.
struct PoseSeries {
  std::vector<double> t, x, y, theta;

  std::size_t size() const { return t.size(); }
  void push_back(double t_s, const PlanarPose& p) {
    t.push_back(t_s);
    x.push_back(p.x_m);
    y.push_back(p.y_m);
    theta.push_back(p.theta_rad);
  }
};

// Linear interpolation of the series at t_s (the sample itself when t_s is a
// sample time). nullopt outside [t.front(), t.back()] or when the two samples
// around t_s are more than max_gap_s apart (a pose across a longer dropout
// would be invented).
std::optional<PlanarPose> interpolate_pose(const PoseSeries& s, double t_s, double max_gap_s);

// Body velocity at t_s from the poses a = p(t_s − h) and b = p(t_s + h),
// h = half_window_s > 0 (interpolated as above):
//   W = (θ_b − θ_a) / 2h,
//   V = ((x_b − x_a) cos θm + (y_b − y_a) sin θm) / 2h / sinc(Δθ/2),
//   θm = (θ_a + θ_b)/2 (the mid heading), sinc(u) = sin u / u,
// i.e. the displacement projected on the mid heading per unit time, corrected
// for the chord of an arc (exact for a constant-velocity arc; the correction
// is < 0.02 % at 0.6 rad/s over 0.1 s). nullopt when a pose is missing or the
// robot turns by more than π within the window (no usable chord).
std::optional<filters::BodyVelocity> central_difference_velocity(const PoseSeries& s, double t_s,
                                                                 double half_window_s, double max_gap_s);

}  // namespace odotune::objectives
