// Unscented Kalman filter on the body velocities (V, W) of a
// differential-drive robot, the fusion filter of Fariña, Acosta, Toledo &
// Acosta, "Improving Odometric Model Performance Based on LSTM Networks",
// Sensors 2023, 23, 961 (../shared/papers/002_*.txt, §1 and Fig. 1):
//
//   state      x = (V, W)                         [m/s, rad/s]
//   model      x_k = x_{k−1} + n,  n ~ N(0, Q·Δt)  ("uniform rectilinear
//              motion": constant velocity; Q is a rate [(m/s)²/s, (rad/s)²/s])
//   measure    odometry z = (V, W), covariance R_odo (static or the slip
//              detector's); external (lidar scan matching) z = (V, W), R_ext;
//              gyro z = W, σ²_gyro.
//
// The sigma points are the scaled unscented transform of Wan & van der Merwe
// (2000, the paper's ref. [2]; eqs. 15–17 of "The Unscented Kalman Filter
// for Nonlinear Estimation"), with parameters α, β, κ. Both models are linear,
// so the filter equals the Kalman filter to rounding (a test checks it); the
// unscented form is kept because it is the paper's filter and lets a
// nonlinear measurement slot in unchanged.
//
// Contract: a value type over fixed-size Eigen types; takes samples and Δt,
// never a track; no I/O. The pose is not part of the state: it is integrated
// from the filtered velocities by integrate_pose (paper eq. 3).
#pragma once

#include <string>

#include <Eigen/Core>

#include <odotune/filters/odometry_params.h>

namespace odotune::filters {

// Named state indices (no magic numbers in the maths).
enum VelocityIndex : int { kV = 0, kW = 1 };
using Velocity = Eigen::Vector2d;     // (V [m/s], W [rad/s])
using VelocityCov = Eigen::Matrix2d;  // [(m/s)², (m/s)(rad/s); ·, (rad/s)²]

struct UkfParams {
  double q_v_m2_s3 = 0.05;   // process-noise rate of V [(m/s)²/s]: P_VV grows by q·Δt
  double q_w_rad2_s3 = 0.1;  // process-noise rate of W [(rad/s)²/s]
  // Scaled unscented transform (Wan & van der Merwe 2000). Defaults: α = 1,
  // β = 2 (Gaussian prior), κ = 0; for a 2-D state these keep every weight
  // finite and the centre weight 0.
  double alpha = 1.0;
  double beta = 2.0;
  double kappa = 0.0;
  Velocity initial_state = Velocity::Zero();
  VelocityCov initial_cov = VelocityCov::Identity() * 1e-2;  // "at rest, ±0.1 m/s, ±0.1 rad/s"

  // Finite, q ≥ 0, 0 < α ≤ 1, β ≥ 0, n + κ > 0, initial_cov symmetric
  // positive definite; `why` names the bad value.
  bool IsValid(std::string* why) const;
};

class VelocityUkf {
 public:
  // Throws std::invalid_argument with IsValid's message.
  explicit VelocityUkf(const UkfParams& params);

  // Time update over dt_s ≥ 0: sigma points through the constant-velocity
  // model, P ← Σ w_c (χ − x̄)(χ − x̄)ᵀ + Q·dt_s.
  void predict(double dt_s);
  // Full (V, W) measurement (odometry or external) with covariance R (SPD).
  void update(const Velocity& z, const VelocityCov& R);
  // Yaw-rate measurement (gyro) of variance var > 0 [(rad/s)²].
  void update_yaw_rate(double w_rad_s, double var);

  const Velocity& state() const { return x_; }
  const VelocityCov& cov() const { return P_; }
  // False once the state or covariance is non-finite or P is not positive
  // definite; sticks.
  bool healthy() const { return healthy_; }

 private:
  UkfParams p_;
  Velocity x_;
  VelocityCov P_;
  bool healthy_ = true;
};

// Planar pose integrated from body velocities, paper eq. 3 (Euler: the
// heading at the start of the step):
//   θ ← θ + W·Δt,  X ← X + V·cos θ_k·Δt,  Y ← Y + V·sin θ_k·Δt.
// (PlanarPose: odotune/filters/odometry_params.h.)
PlanarPose integrate_pose(const PlanarPose& pose, double v_m_s, double w_rad_s, double dt_s);

// Normalised estimation error squared e ᵀ P⁻¹ e of one estimate (paper
// eq. 10 before averaging); NaN when P is not positive definite.
double nees(const Velocity& truth, const Velocity& estimate, const VelocityCov& P);

}  // namespace odotune::filters
