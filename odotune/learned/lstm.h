// Small single-layer LSTM networks with one dense output neuron, as used by
// Fariña et al., "Improving Odometric Model Performance Based on LSTM
// Networks", Sensors 2023, 23, 961, §4 (velocity nets, Fig. 4) and §4.1 (slip
// detector, Fig. 6).
//
// One cell step (paper eqs. 5–8, gates in Keras order i, f, c, o):
//   i_t = σ(W_iᵀ x_t + U_iᵀ h_{t−1} + b_i)          (eq. 6, input gate)
//   f_t = σ(W_fᵀ x_t + U_fᵀ h_{t−1} + b_f)          (eq. 5, forget gate)
//   g_t = tanh(W_cᵀ x_t + U_cᵀ h_{t−1} + b_c)       (eq. 6, candidate C̃_t)
//   o_t = σ(W_oᵀ x_t + U_oᵀ h_{t−1} + b_o)          (eq. 8, output gate)
//   c_t = f_t ⊙ c_{t−1} + i_t ⊙ g_t                 (eq. 7)
//   h_t = o_t ⊙ tanh(c_t)                           (eq. 8)
// with h_0 = c_0 = 0, σ the logistic sigmoid (tanh and σ evaluated from exp(),
// lstm_detail below) (Keras' default
// recurrent_activation). The output is the dense neuron d·h_T + d_0 on the
// last hidden state, linear or ReLU (paper §4: linear for V/W; §4.1: ReLU
// for the detector), in standardised target units; LstmNet::predict maps it
// back to raw units (paper eq. 4 inverted, "de-normalisation", §4.1).
//
// Header-only: lstm_forward is templated on the scalar type so that
// ceres::Jet flows through it (odotune/learned/lstm_training.h). No I/O here
// (odotune/results/lstm_json.h reads and writes the weights).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <sstream>
#include <string>
#include <utility>

#include <odotune/core/why.h>

namespace odotune::learned {

enum class OutputActivation { linear, relu };

// Flat weight layout of one LSTM layer (I inputs, H units) followed by the
// dense output neuron. It is exactly Keras' `get_weights()` of
// LSTM(H) + Dense(1), each array flattened row-major and concatenated, so
// weights trained elsewhere can be pasted in:
//   [kKernel,    kKernel + I·4H)     W, input kernel, shape (I, 4H):
//                                    W[k][g·H + j] at kKernel + k·4H + g·H + j
//   [kRecurrent, kRecurrent + H·4H)  U, recurrent kernel, shape (H, 4H):
//                                    U[m][g·H + j] at kRecurrent + m·4H + g·H + j
//   [kBias,      kBias + 4H)         b, shape (4H): b[g·H + j] at kBias + g·H + j
//   [kDense,     kDense + H)         d, dense kernel (H, 1): d[j] at kDense + j
//   kDenseBias                       d_0, dense bias
// where k indexes inputs, m and j units, and g the gate: 0 = i (input),
// 1 = f (forget), 2 = c (candidate), 3 = o (output).
template <int I, int H>
struct LstmLayout {
  static_assert(I >= 1 && H >= 1, "an LSTM needs at least one input and one unit");
  static constexpr int kInputs = I, kHidden = H;
  static constexpr int kGates = 4 * H;  // pre-activations per step
  static constexpr int kKernel = 0;
  static constexpr int kRecurrent = kKernel + I * kGates;
  static constexpr int kBias = kRecurrent + H * kGates;
  static constexpr int kDense = kBias + kGates;
  static constexpr int kDenseBias = kDense + H;
  static constexpr int kCount = 4 * H * (I + H + 1) + H + 1;  // <3,5> → 186, <5,10> → 651
  static_assert(kDenseBias + 1 == kCount, "layout offsets must tile the weight vector");
};

namespace lstm_detail {

// Logistic sigmoid, written in the two branches that never overflow exp():
// for z < 0 as e^z / (1 + e^z). The branch compares the scalar part only
// (ceres::Jet's comparison), so the derivative is that of σ on either side.
template <typename T>
T sigmoid(const T& z) {
  using std::exp;
  if (z >= T(0.0)) return T(1.0) / (T(1.0) + exp(-z));
  const T e = exp(z);
  return e / (T(1.0) + e);
}

// tanh from one exp(), in the branch that never overflows:
//   tanh(z) = (1 − e)/(1 + e), e = exp(−2|z|), sign restored.
// Hand-written rather than std::tanh because glibc's tanh (via expm1) is
// several times slower than exp and dominated training and inference time
// (perf on the BPTT training loop); the absolute error stays at a few ulp of
// 1, which is all an LSTM's state needs (the relative error near z = 0 is
// larger, harmless here). Works for ceres::Jet (derivative 1 − tanh²).
template <typename T>
T tanh_exp(const T& z) {
  using std::exp;
  if (z >= T(0.0)) {
    const T e = exp(T(-2.0) * z);
    return (T(1.0) - e) / (T(1.0) + e);
  }
  const T e = exp(T(2.0) * z);
  return (e - T(1.0)) / (e + T(1.0));
}

// A double as text for messages (std::to_string's fixed 6 decimals hide small values).
inline std::string number_text(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

}  // namespace lstm_detail

// Forward pass over one standardised window x (window × I doubles, row-major,
// oldest sample first), zero initial h and c, paper eqs. 5–8. Returns the
// output neuron in standardised target units (before de-normalisation), with
// the ReLU max(0, ·) applied when act == relu (derivative 0 below zero).
// `weights` has LstmLayout<I, H>::kCount entries. Templated on T so Ceres Jets
// flow through it (weights T, inputs double). Does not allocate.
template <int I, int H, typename T>
T lstm_forward(const T* weights, const double* x, int window, OutputActivation act) {
  using L = LstmLayout<I, H>;
  std::array<T, H> h, c;
  h.fill(T(0.0));
  c.fill(T(0.0));
  std::array<T, L::kGates> z;
  for (int t = 0; t < window; ++t) {
    const double* xt = x + static_cast<long>(t) * I;
    for (int n = 0; n < L::kGates; ++n) z[n] = weights[L::kBias + n];
    for (int k = 0; k < I; ++k) {
      const T* wk = weights + L::kKernel + k * L::kGates;
      for (int n = 0; n < L::kGates; ++n) z[n] += wk[n] * xt[k];
    }
    for (int m = 0; m < H; ++m) {
      const T* um = weights + L::kRecurrent + m * L::kGates;
      const T hm = h[m];
      for (int n = 0; n < L::kGates; ++n) z[n] += um[n] * hm;
    }
    for (int j = 0; j < H; ++j) {
      const T i_gate = lstm_detail::sigmoid(z[j]);
      const T f_gate = lstm_detail::sigmoid(z[H + j]);
      const T g_cand = lstm_detail::tanh_exp(z[2 * H + j]);
      const T o_gate = lstm_detail::sigmoid(z[3 * H + j]);
      c[j] = f_gate * c[j] + i_gate * g_cand;
      h[j] = o_gate * lstm_detail::tanh_exp(c[j]);
    }
  }
  T out = weights[L::kDenseBias];
  for (int j = 0; j < H; ++j) out += weights[L::kDense + j] * h[j];
  if (act == OutputActivation::relu && out < T(0.0)) return T(0.0);
  return out;
}

// A trained network with its standardisation (paper eq. 4: z = (s − μ)/σ per
// input feature; the output is de-normalised as y = output_mean + output_sd·net).
template <int I, int H>
struct LstmNet {
  static constexpr int kInputs = I, kHidden = H, kWeights = LstmLayout<I, H>::kCount;
  // Maximum window length predict() accepts (its standardised copy lives on
  // the stack so that predict does not allocate).
  static constexpr int kMaxWindow = 256;

  std::array<double, kWeights> weights{};          // layout: LstmLayout<I, H>
  std::array<double, I> input_mean{}, input_sd{};  // paper eq. 4 (sd > 0; a constant input gets sd 1)
  double output_mean = 0.0, output_sd = 1.0;       // y = output_mean + output_sd · net
  OutputActivation activation = OutputActivation::linear;
  int window = 20;  // samples per window (paper: 20 at 10 Hz)

  LstmNet() { input_sd.fill(1.0); }

  // raw_window: window × I raw samples, row-major, oldest first. Returns the
  // prediction in raw target units. Requires IsValid(); does not allocate.
  double predict(const double* raw_window) const {
    std::array<double, static_cast<std::size_t>(kMaxWindow) * I> z;
    std::array<double, I> inv_sd;
    for (int k = 0; k < I; ++k) inv_sd[k] = 1.0 / input_sd[k];
    for (int t = 0; t < window; ++t)
      for (int k = 0; k < I; ++k) {
        const int n = t * I + k;
        z[n] = (raw_window[n] - input_mean[k]) * inv_sd[k];
      }
    return output_mean + output_sd * lstm_forward<I, H, double>(weights.data(), z.data(), window, activation);
  }

  // Standardises a raw window (window × I) into `out` (same size), eq. 4.
  void standardise(const double* raw_window, double* out) const {
    for (int t = 0; t < window; ++t)
      for (int k = 0; k < I; ++k) out[t * I + k] = (raw_window[t * I + k] - input_mean[k]) / input_sd[k];
  }

  // Finite weights and standardisation, sd > 0, 1 ≤ window ≤ kMaxWindow.
  bool IsValid(std::string* why) const {
    if (window < 1 || window > kMaxWindow)
      return core::invalid(why, "window = " + std::to_string(window) + ": expected 1.." +
                                    std::to_string(kMaxWindow));
    for (int n = 0; n < kWeights; ++n)
      if (!std::isfinite(weights[n]))
        return core::invalid(why, "weights[" + std::to_string(n) + "] is not finite");
    for (int k = 0; k < I; ++k) {
      if (!std::isfinite(input_mean[k]))
        return core::invalid(why, "input_mean[" + std::to_string(k) + "] is not finite");
      if (!(input_sd[k] > 0.0) || !std::isfinite(input_sd[k]))
        return core::invalid(why, "input_sd[" + std::to_string(k) + "] = " +
                                      lstm_detail::number_text(input_sd[k]) + ": expected a finite value > 0");
    }
    if (!std::isfinite(output_mean)) return core::invalid(why, "output_mean is not finite");
    if (!(output_sd > 0.0) || !std::isfinite(output_sd))
      return core::invalid(why, "output_sd = " + lstm_detail::number_text(output_sd) +
                                    ": expected a finite value > 0");
    return true;
  }
};

using VelocityNet = LstmNet<3, 5>;  // (Δct_r, Δct_l, previous V or W) → V or W  [paper §4, Fig. 4]
using SlipNet = LstmNet<5, 10>;     // (P_r, P_l, Δct_r, Δct_l, previous variance) → variance [§4.1]

}  // namespace odotune::learned
