// The fusion UKF of Fariña et al., Sensors 2023, 23, 961 (velocity_ukf.h)
// with the pose in its state, so that absolute position fixes (GNSS, UWB,
// motion capture) enter the fusion:
//
//   state      x = (X, Y, θ, V, W)                          [m, m, rad, m/s, rad/s]
//   model      X_k = X + V·Δt·cos(θ + W·Δt/2),  Y_k = Y + V·Δt·sin(θ + W·Δt/2),
//              θ_k = θ + W·Δt,  V_k = V + n_V,  W_k = W + n_W,
//              n ~ N(0, diag(q_v, q_w)·Δt)  (constant velocity, as velocity_ukf.h),
//              plus q_xy·Δt on X and Y (a little, keeps P well conditioned)
//   measure    odometry or external z = (V, W), R;  gyro z = W, σ²;
//              position fix z = (X, Y), R_fix.
//
// The prediction is the scaled unscented transform (odotune/filters/unscented.h)
// through the unicycle model above; every measurement is linear in the
// state, for which the unscented update is the Kalman update (velocity_ukf.h
// says the same). θ is kept unwrapped; no measurement observes it, so no
// angle wraps enter the innovations.
//
// Contract: a value type over fixed-size Eigen types; samples and Δt in,
// never a track; no I/O.
#pragma once

#include <string>

#include <Eigen/Core>

namespace odotune::filters {

enum PoseVelocityIndex : int { kPx = 0, kPy = 1, kPtheta = 2, kPv = 3, kPw = 4 };
using PoseVelocity = Eigen::Matrix<double, 5, 1>;
using PoseVelocityCov = Eigen::Matrix<double, 5, 5>;

struct PoseUkfParams {
  double q_v_m2_s3 = 0.05;                      // process-noise rate of V [(m/s)²/s] (as UkfParams)
  double q_w_rad2_s3 = 0.1;                     // of W [(rad/s)²/s]
  double q_xy_m2_s = 1e-4;                      // of X and Y [m²/s]
  double alpha = 1.0, beta = 2.0, kappa = 0.0;  // scaled unscented transform
  PoseVelocity initial_state = PoseVelocity::Zero();
  PoseVelocityCov initial_cov = PoseVelocityCov::Identity() * 1e-2;
  // Finite, q ≥ 0, 0 < α ≤ 1, β ≥ 0, n + κ > 0, initial_cov symmetric
  // positive definite; `why` names the bad value.
  bool IsValid(std::string* why) const;
};

class PoseVelocityUkf {
 public:
  // Throws std::invalid_argument with IsValid's message.
  explicit PoseVelocityUkf(const PoseUkfParams& params);

  void predict(double dt_s);                                                     // dt_s ≥ 0
  void update_velocity(double v_m_s, double w_rad_s, const Eigen::Matrix2d& R);  // odometry or external
  void update_yaw_rate(double w_rad_s, double var);                              // gyro
  void update_position(double x_m, double y_m, const Eigen::Matrix2d& R);        // a fix

  const PoseVelocity& state() const { return x_; }
  const PoseVelocityCov& cov() const { return P_; }
  // False once the state or covariance is non-finite or P is not positive
  // definite; sticks.
  bool healthy() const { return healthy_; }

 private:
  PoseUkfParams p_;
  PoseVelocity x_;
  PoseVelocityCov P_;
  bool healthy_ = true;
};

}  // namespace odotune::filters
