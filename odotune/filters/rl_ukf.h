// robot_localization's unscented Kalman filter (ukf_node; behaviour read from
// cra-ros-pkg/robot_localization's ukf.cpp and filter_base.cpp, noetic-devel):
// the state, motion model and measurements of odotune/filters/rl_ekf.h through the
// scaled unscented transform (Wan & van der Merwe, "The Unscented Kalman
// Filter for Nonlinear Estimation", 2000) with n = 15 and 2n + 1 sigma points.
//
//   λ = α²(n + κ) − n;  W₀ = λ/(n + λ),  W₀ᶜ = W₀ + 1 − α² + β,
//   Wᵢ = Wᵢᶜ = 1/(2(n + λ)),  i = 1 … 2n
//   sigma points: χ₀ = x, χ₁…ₙ = x + Lᵢ, χₙ₊₁…₂ₙ = x − Lᵢ,  L·Lᵀ = (n + λ)·P
//   predict:  χᵢ ← f(χᵢ, Δt);  x = Σ Wᵢχᵢ (roll, pitch, yaw: atan2 of the
//             weighted sines and cosines);  P = Σ Wᵢᶜ(χᵢ − x)(χᵢ − x)ᵀ + Δt·Q
//   correct:  ẑ = Σ Wᵢ H·χᵢ (angles as above);  P_zz = Σ Wᵢᶜ(Hχᵢ − ẑ)(Hχᵢ − ẑ)ᵀ,
//             P_xz = Σ Wᵢᶜ(χᵢ − x)(Hχᵢ − ẑ)ᵀ;  K = P_xz·(P_zz + R)⁻¹,
//             x ← x + K·(z − ẑ),  P ← P − K·P_zz·Kᵀ
//             unless (z − ẑ)ᵀ(P_zz + R)⁻¹(z − ẑ) ≥ threshold².
//
// As ukf_node runs it, and so unlike the textbook filter:
// - Q is added after the sigma points are propagated, and the first correction
//   after a prediction uses the propagated points (Q not in them); a further
//   correction at the same time draws new points from x and P.
// - The covariance update subtracts K·P_zz·Kᵀ, not K·(P_zz + R)·Kᵀ
//   (robot_localization issue #711).
// - In P_xz the wrapped entries of χᵢ − x are those at the positions, within
//   the measured subset, of its angle members (state entries 0, 1, … rather
//   than roll, pitch, yaw).
// - Before the first prediction the sigma points are all zero.
// - With a small α, W₀ ≈ −1/α²: once an angle's variance passes 2 rad² its
//   weighted mean points the other way (the weighted cosines sum to about
//   1 − var/2), and the filter diverges. A heading that nothing measures gets
//   there (the Husky's file without its GPS, in about 30 s).
// Times are integer nanoseconds; no I/O and no allocation per step.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include <odotune/filters/rl_ekf.h>

namespace odotune::filters::rl {

struct RlUkfParams {
  RlEkfParams filter;    // Q, the initial covariance and state, dynamic Q
  double alpha = 0.001;  // the sigma points' spread (ukf_node's ~alpha)
  double kappa = 0.0;    // secondary scaling (~kappa)
  double beta = 2.0;     // prior knowledge of the distribution; 2 for a Gaussian (~beta)

  // Also refuses α ≤ 0, n + κ ≤ 0 (no real sigma points) and non-finite values.
  bool IsValid(std::string* why) const;
};

constexpr int kSigmaPoints = 2 * kStateSize + 1;

// The unscented transform's weights for those parameters.
struct UkfWeights {
  double lambda = 0.0;
  std::array<double, kSigmaPoints> state{};
  std::array<double, kSigmaPoints> covariance{};
};
UkfWeights ukf_weights(double alpha, double kappa, double beta);

class RlUkf {
 public:
  // Throws std::invalid_argument for parameters that are not valid.
  explicit RlUkf(const RlUkfParams& params);

  // As RlEkf::process: the first measurement initialises; later ones predict
  // over the time since the last measurement when it is positive, then
  // correct. Returns false when the Mahalanobis test rejected it.
  bool process(const Measurement& m);
  // As RlEkf::predict_to.
  void predict_to(std::int64_t time_ns);

  void predict(double dt_s);
  bool correct(const Measurement& m);

  bool initialized() const { return initialized_; }
  std::int64_t last_time_ns() const { return last_time_ns_; }
  const State& state() const { return x_; }
  const Cov& cov() const { return P_; }
  // FilterBase::setEstimateErrorCovariance.
  void set_cov(const Cov& P) { P_ = P; }
  void set_last_time_ns(std::int64_t t) { last_time_ns_ = t; }
  // As RlEkf::restore. The sigma points and whether they are the last
  // prediction's stay as they are, as the node's setState leaves them.
  void restore(const State& x, const Cov& P, std::int64_t last_ns) {
    x_ = x;
    P_ = P;
    last_time_ns_ = last_ns;
  }
  const UkfWeights& weights() const { return w_; }

 private:
  void draw_sigma_points();

  Cov Q_;
  bool dynamic_q_;
  UkfWeights w_;
  State x_;
  Cov P_;
  std::array<State, kSigmaPoints> sigma_;
  bool uncorrected_ = true;  // the points are the last prediction's
  bool initialized_ = false;
  std::int64_t last_time_ns_ = 0;
};

}  // namespace odotune::filters::rl
