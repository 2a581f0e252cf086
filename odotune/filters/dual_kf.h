// Dual Kalman filter calibration of the odometry parameters: one filter for
// the body velocities x = (V, W), one for the parameters θ = (R_R, R_L, D),
// run side by side (Wan & Nelson, "Dual Kalman filtering methods for
// nonlinear prediction, smoothing, and estimation", NIPS 2000); the baseline
// of Fariña, Toledo & Acosta (RA-L 2026, Table II, Figure 8).
//
// One iteration (step()) per external velocity measurement z = (V_m, W_m):
//   state filter:     x⁻ = h(θ̂, ω) (the odometry velocities with the current
//                     parameters), P⁻ = P_odo; update with z (R = diag(var_v,
//                     var_w)) → x̂, P_x.
//   parameter filter: θ⁻ = θ̂ (random walk), P_θ⁻ = P_θ + Q_θ·dt (or, with
//                     fading_memory, P_θ⁻ = e^{dt/M}·P_θ); update with
//                     the state filter's x̂ as the measurement of h(θ, ω)
//                     (extended KF: H = ∂h/∂θ at θ⁻), measurement covariance
//                     P_x + P_odo.
// Both covariance updates use the Joseph form (I − KH)P(I − KH)ᵀ + KRKᵀ, and
// P_θ is symmetrised after each step, so the covariances stay symmetric
// positive definite. The estimate's velocity is h(θ̂, ω) with the updated θ̂,
// its sds √diag(P_θ); step() throws std::invalid_argument for a sample that
// breaks CalibSample's contract.
// h(θ, ω) = ((ω_r R_R + ω_l R_L)/2, (ω_r R_R − ω_l R_L)/D).
#pragma once

#include <string>

#include <Eigen/Core>

#include <odotune/filters/odometry_params.h>
#include <odotune/filters/pf_evolution.h>

namespace odotune::filters {

// Named indices of the two filters' states.
enum DkfVelocityIndex : int { kDkfV = 0, kDkfW = 1, kDkfVelocityDim = 2 };
enum DkfParamIndex : int { kDkfRadiusRight = 0, kDkfRadiusLeft = 1, kDkfWheelBase = 2, kDkfParamDim = 3 };

using DkfVelocity = Eigen::Matrix<double, kDkfVelocityDim, 1>;
using DkfVelocityCov = Eigen::Matrix<double, kDkfVelocityDim, kDkfVelocityDim>;
using DkfParams = Eigen::Matrix<double, kDkfParamDim, 1>;
using DkfParamCov = Eigen::Matrix<double, kDkfParamDim, kDkfParamDim>;
using DkfJacobian = Eigen::Matrix<double, kDkfVelocityDim, kDkfParamDim>;

struct DualKfParams {
  OdometryParams initial{0.32, 0.32, 0.65};    // θ̂₀ (wheelchair nominal)
  double initial_sd_radius_m = 0.0087;         // √P_θ₀ of each radius (uniform ±15 mm)
  double initial_sd_wheel_base_m = 0.058;      // √P_θ₀ of D (uniform ±0.1 m)
  double odometry_sd_v_m_s = 0.02;             // √P_odo of V [m/s]
  double odometry_sd_w_rad_s = 0.02;           // √P_odo of W [rad/s]
  double radius_walk_m_per_sqrt_s = 2e-4;      // √Q_θ of each radius [m/√s]
  double wheel_base_walk_m_per_sqrt_s = 2e-4;  // √Q_θ of D [m/√s]
  // false: the random walk above (the paper's baseline). true: no walk; the
  // parameter covariance fades instead, P_θ⁻ = e^{dt/M}·P_θ bounded by the
  // initial covariance, with the memory M and its change test of
  // odotune/filters/pf_evolution.h (the PF's evidence evolution).
  bool fading_memory = true;
  EvidenceMemoryParams evidence;

  // True when usable; otherwise *why names the first bad value, e.g.
  // "initial.wheel_base_m = 0 must be a finite number > 0". sds > 0, walks ≥ 0.
  bool IsValid(std::string* why) const;
};

// ∂h/∂θ at θ for wheel rates ω (checked against numerical differentiation in
// the tests).
DkfJacobian dkf_jacobian(const DkfParams& theta, double omega_l_rad_s, double omega_r_rad_s);

class DualKf {
 public:
  // Throws std::invalid_argument with IsValid's message.
  explicit DualKf(const DualKfParams& params);

  const CalibEstimate& step(const CalibSample& sample);
  const CalibEstimate& estimate() const { return estimate_; }
  const DkfParamCov& param_covariance() const { return P_theta_; }
  long iterations() const { return iteration_; }
  // As PfCalibrator's (odotune/filters/memory_pair.h).
  double last_log_predictive() const { return last_log_predictive_; }
  void set_memory(const EvidenceMemoryParams& p) { memory_ = EvidenceMemory(p); }
  double memory_s() const { return memory_.memory_s(); }

 private:
  DualKfParams params_;
  DkfParams theta_;
  DkfParamCov P_theta_;
  CalibEstimate estimate_;
  long iteration_ = 0;
  EvidenceMemory memory_;
  double last_log_predictive_ = 0.0;
};

}  // namespace odotune::filters
