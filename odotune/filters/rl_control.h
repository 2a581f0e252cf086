// robot_localization's control term (FilterBase::prepareControl and
// computeControlAcceleration, filter_base.cpp and filter_base.h, read for
// behaviour): the last commanded body velocity turned into the acceleration
// the EKF's prediction assumes.
//
//   e = u − v;  set point s = u when |e| ≤ |u| + 0.01, else 0;
//   decelerating when |s| < |v| (deceleration limit and gain, else acceleration's);
//   a = clamp(gain·e, −limit, limit)
//
// for each controlled member of (vx, vy, vz, vroll, vpitch, vyaw); u is 0 once
// the command is older than the timeout. The EKF then sets a_x, a_y, a_z to a
// (where controlled) and adds a·Δt to the angular rates before it projects
// the state (ekf.cpp's predict); ukf_node computes a but its prediction does
// not use it.
#pragma once

#include <array>
#include <cstdint>
#include <string>

namespace odotune::filters::rl {

// Members of a command (robot_localization's ControlMembers).
enum ControlMember : int { kCVx = 0, kCVy, kCVz, kCVroll, kCVpitch, kCVyaw };
constexpr int kControlSize = 6;
using ControlVector = std::array<double, kControlSize>;

// How the node's clock decides that a command timed out: ROS 1's node
// compares |t − t_u| with the timeout, ROS 2's t − t_u (a command stamped
// after the measurement never times out there).
enum class ControlTimeout { absolute, forward };

struct RlControlParams {
  std::array<bool, kControlSize> update{};  // control_config
  std::int64_t timeout_ns = 0;              // control_timeout
  ControlTimeout timeout_rule = ControlTimeout::absolute;
  ControlVector acceleration_limits{}, acceleration_gains{};  // [m/s², rad/s²], [1/s]
  ControlVector deceleration_limits{}, deceleration_gains{};

  // Refuses negative or non-finite limits and gains and a negative timeout.
  bool IsValid(std::string* why) const;
};

// The latest command the node has: body velocities [m/s, rad/s] and their time.
struct Command {
  ControlVector u{};
  std::int64_t time_ns = 0;
};

// computeControlAcceleration for one member at velocity `v` under command `u`.
double control_acceleration(double v, double u, double acceleration_limit, double acceleration_gain,
                            double deceleration_limit, double deceleration_gain);

// prepareControl at `reference_ns` (the measurement's or the prediction's
// time) from the body velocities `v` (vx … vyaw): the acceleration of each
// controlled member, 0 elsewhere.
ControlVector control_accelerations(const RlControlParams& p, const Command& c, const ControlVector& v,
                                    std::int64_t reference_ns);

}  // namespace odotune::filters::rl
