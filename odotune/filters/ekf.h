// EKF on the planar pose (x, y, θ): prediction from wheel travel, correction
// by absolute position fixes (Kovacs et al. §2.2; Thrun, Burgard & Fox,
// "Probabilistic Robotics", Table 3.3 for the EKF equations).
//
// This is the straightforward one-step-at-a-time filter: the form a robot runs
// online, and the reference that the segment-batched replay used by the tuner
// (odotune/filters/ekf_segments.h) must reproduce. It takes samples, never a track,
// and does no I/O.
#pragma once

#include <string>

#include <Eigen/Core>
#include <Eigen/LU>  // fixed-size closed-form inverse() and determinant()

#include <odotune/filters/diff_drive.h>
#include <odotune/filters/ekf_noise.h>

namespace odotune::filters {

using Position = Eigen::Vector2d;

// Why a run stopped being a usable filter.
enum class Divergence { none, non_finite, covariance_not_pd };
std::string_view to_string(Divergence d);

struct EkfParams {
  NoiseParams noise;
  double wheel_base_m = 0.3;  // D of the motion model
  Pose initial_pose = Pose::Zero();
  // Initial covariance; the default says "we know where we start to 1 cm and 1°".
  StateCov initial_cov = (Pose() << 1e-4, 1e-4, 3.0e-4).finished().asDiagonal();

  bool IsValid(std::string* why) const;
};

// Positive definiteness of a symmetric 3 × 3 matrix by Sylvester's criterion
// (leading minors > 0); false for non-finite entries.
bool is_positive_definite(const StateCov& P);

class Ekf {
 public:
  explicit Ekf(const EkfParams& params);

  // Prediction: x ← f(x, u), P ← F·P·Fᵀ + R(u, |ω_z|). Returns the process
  // noise R it added (for reports such as odotune/objectives/process_noise_rate.h).
  StateCov predict(WheelTravel u, double abs_yaw_rate_rad_s);
  // Correction by a position fix z = (x, y) [m]:
  //   S = H·P·Hᵀ + Q, K = P·Hᵀ·S⁻¹, x ← x + K·(z − H·x), P ← P − K·S·Kᵀ.
  void update(const Position& z);
  // The same with this fix's own measurement variances q_x, q_y [m²] (e.g. a
  // GNSS receiver's covariance) in place of the noise model's.
  void update(const Position& z, double q_x_m2, double q_y_m2);

  const Pose& pose() const { return x_; }
  const StateCov& cov() const { return P_; }
  // Checks the state and covariance; the first problem found sticks.
  Divergence check();
  Divergence divergence() const { return div_; }

 private:
  NoiseParams noise_;
  double wheel_base_m_;
  Pose x_;
  StateCov P_;
  Divergence div_ = Divergence::none;
};

}  // namespace odotune::filters
