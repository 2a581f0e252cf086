// robot_localization's extended Kalman filter (Moore & Stouch, "A Generalized
// Extended Kalman Filter Implementation for the Robot Operating System",
// IAS-13, 2014; behaviour read from cra-ros-pkg/robot_localization's
// filter_base.cpp and ekf.cpp): a 15-D state of pose, body-frame velocities
// and linear accelerations under an omnidirectional kinematic model, corrected
// by masked measurements of any subset of the state.
//
//   predict:  x ← f(x, Δt) = A(x, Δt)·x,  P ← J·P·Jᵀ + Δt·Q   (Q or its dynamic form)
//   correct:  S = H·P·Hᵀ + R, K = P·Hᵀ·S⁻¹, x ← x + K·(z − H·x) (angles wrapped),
//             P ← (I − K·H)·P·(I − K·H)ᵀ + K·R·Kᵀ
//             unless the squared Mahalanobis distance νᵀ·S⁻¹·ν ≥ threshold².
//
// The node's first measurement initialises the fused members and their
// covariance block instead of correcting. Times are integer nanoseconds, as the
// node's rclcpp::Time; no I/O and no allocation per step.
//
// P is kept exactly symmetric: each update computes its lower triangle and
// mirrors it, so Q, the initial covariance and the first measurement's block
// enter through their symmetric part ((A + Aᵀ)/2, which is A itself for the
// symmetric matrices a covariance is). robot_localization updates all of P;
// the two differ by rounding only.
//
// RlEkfLanes runs up to kLanes such filters in lock step, one per SIMD lane:
// filters that see the same measurements at the same times (one replay
// schedule) with different noise settings, as the candidates of a tune do.
// Every lane computes exactly what an RlEkf with its settings computes, bit
// for bit (the same operations in the same order, one template for both).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <string>

#include <optional>

#include <Eigen/Core>

#include <odotune/filters/rl_control.h>

namespace odotune::filters::rl {

// State members (robot_localization's StateMembers).
enum Member : int {
  kX = 0,
  kY,
  kZ,
  kRoll,
  kPitch,
  kYaw,
  kVx,
  kVy,
  kVz,
  kVroll,
  kVpitch,
  kVyaw,
  kAx,
  kAy,
  kAz,
};
constexpr int kStateSize = 15;

using State = Eigen::Matrix<double, kStateSize, 1>;
using Cov = Eigen::Matrix<double, kStateSize, kStateSize>;
using Mask = std::array<bool, kStateSize>;

// One measurement as the node enqueues it: all 15 members, its covariance and
// the members to fuse; `mahalanobis_threshold` in standard deviations.
struct Measurement {
  std::int64_t time_ns = 0;
  State z = State::Zero();
  Cov R = Cov::Zero();
  Mask mask{};
  double mahalanobis_threshold = std::numeric_limits<double>::max();
};

struct RlEkfParams {
  Cov process_noise = Cov::Zero();           // Q per second [unit²/s]
  Cov initial_cov = Cov::Identity() * 1e-9;  // P before the first measurement
  bool dynamic_process_noise = false;        // scale Q's pose block by |velocity|²
  State initial_state = State::Zero();
  // use_control's term (odotune/filters/rl_control.h); none: the prediction has none.
  // RlEkfLanes refuses it.
  std::optional<RlControlParams> control;

  bool IsValid(std::string* why) const;
};

// The transition of the kinematic model over Δt: A (with x' = A·x) and its
// Jacobian J = ∂f/∂x at x (ekf.cpp's transfer function and its Jacobian).
struct Transition {
  Cov A;
  Cov J;
};
Transition transition(const State& x, double dt_s);
// f(x, Δt) = A(x, Δt)·x, the angles not wrapped: the projection of one state,
// as ukf.cpp projects each sigma point (the same terms as transition's A).
State advance(const State& x, double dt_s);

// Wraps an angle to [−π, π] as ROS's angles::normalize_angle does (fmod), which
// the node's replay must match bit for bit (odotune/core/angles.h is std::remainder).
double normalize_angle(double a);

class RlEkf {
 public:
  explicit RlEkf(const RlEkfParams& params);

  // FilterBase::processMeasurement: the first measurement initialises; later
  // ones predict over the time since the last measurement when it is positive,
  // then correct. The last measurement time moves only forward. Returns false
  // when the Mahalanobis test rejected the measurement.
  bool process(const Measurement& m);
  // The node's prediction to `time_ns` when no measurement came for its sensor
  // timeout (or with predict_to_current_time); sets the last measurement time.
  void predict_to(std::int64_t time_ns);

  // A prediction over dt_s from the last measurement time (its reference
  // time for the control term).
  void predict(double dt_s);
  bool correct(const Measurement& m);
  // FilterBase::setControl: the command the next predictions use (with
  // RlEkfParams::control; ignored without).
  void set_command(const Command& c) { command_ = c; }

  bool initialized() const { return initialized_; }
  std::int64_t last_time_ns() const { return last_time_ns_; }
  const State& state() const { return x_; }
  const Cov& cov() const { return P_; }
  void set_last_time_ns(std::int64_t t) { last_time_ns_ = t; }
  // The node's revertTo (smooth_lagged_data): a saved state, covariance and
  // last measurement time put back; the command is not.
  void restore(const State& x, const Cov& P, std::int64_t last_ns) {
    x_ = x;
    P_ = P;
    last_time_ns_ = last_ns;
  }

 private:
  void predict_at(double dt_s, std::int64_t reference_ns);

  Cov Q_;
  bool dynamic_q_;
  std::optional<RlControlParams> control_;
  Command command_;
  State x_;
  Cov P_;
  bool initialized_ = false;
  std::int64_t last_time_ns_ = 0;
};

// The lanes of RlEkfLanes: 8 doubles, one AVX-512 register (two AVX2 or four
// SSE2 registers on CPUs without it; odotune/filters/rl_ekf.cpp picks the code for the
// CPU at load time, every version giving the same bits).
constexpr int kLanes = 8;
using Lanes = double __attribute__((vector_size(kLanes * sizeof(double))));

class RlEkfLanes {
 public:
  // One lane per entry of `params` (1 … kLanes); throws std::invalid_argument
  // for another count or invalid parameters.
  explicit RlEkfLanes(std::span<const RlEkfParams> params);

  int lanes() const { return lanes_; }
  // RlEkf::process in every lane: ms[l] is lane l's measurement (throws
  // std::invalid_argument unless there is one per lane). All must have the
  // same time and mask (asserted); their values, covariances and thresholds
  // may differ. Bit l of the result is set when lane l accepted its measurement.
  std::uint32_t process(std::span<const Measurement> ms);
  void predict_to(std::int64_t time_ns);

  bool initialized() const { return initialized_; }
  std::int64_t last_time_ns() const { return last_time_ns_; }
  State state(int lane) const;
  Cov cov(int lane) const;

 private:
  std::uint32_t correct(std::span<const Measurement> ms);
  std::uint32_t correct_lane_by_lane(std::span<const Measurement> ms);
  void set_lane(int lane, const State& x, const Cov& P);

  int lanes_;
  bool initialized_ = false;
  std::int64_t last_time_ns_ = 0;
  std::array<Lanes, kStateSize> x_;
  // Column-major, lane l of entry (i, j) at [j·15 + i][l].
  std::array<Lanes, std::size_t{kStateSize} * std::size_t{kStateSize}> P_, Q_;
  std::int64_t __attribute__((vector_size(kLanes * sizeof(double)))) dynamic_q_;  // all bits set where dynamic
};

}  // namespace odotune::filters::rl
