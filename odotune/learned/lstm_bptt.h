// Value and weight-gradient of lstm_forward by backpropagation
// through time (BPTT, reverse mode).
//
// Why hand-written: Ceres' automatic differentiation is forward mode (Jets),
// so one residual's Jacobian row costs about LstmLayout::kCount forward
// passes (186 for the V/W nets, 651 for the slip detector); Ceres has no
// reverse mode. The network here is one scalar output of ~200 weights, for
// which reverse mode gives the whole row for about three forward passes —
// what lets the nets retrain on the robot in milliseconds. The
// forward-mode path (odotune/learned/lstm_training.h, LstmResidual) remains the
// reference: tests/learned/test_lstm_training.cpp checks this gradient
// against it and against central finite differences.
//
// Backward recursion (derivatives of the output y = d·h_T + d_0 w.r.t. every
// quantity, written δ·; forward quantities as in odotune/learned/lstm.h):
//   δh_T = d,  δc_{T+1}·f_{T+1} := 0
//   δc_t  = δc_{t+1}·f_{t+1} + δh_t · o_t · (1 − tanh²c_t)
//   δz_i = δc_t · g_t · i_t(1 − i_t)        δz_f = δc_t · c_{t−1} · f_t(1 − f_t)
//   δz_c = δc_t · i_t · (1 − g_t²)          δz_o = δh_t · tanh(c_t) · o_t(1 − o_t)
//   δb += δz,  δW += x_t δzᵀ,  δU += h_{t−1} δzᵀ,  δh_{t−1} = U δz
// and δd = h_T, δd_0 = 1. Below the ReLU's zero the whole gradient is 0.
#pragma once

#include <array>
#include <cmath>
#include <vector>

#include <odotune/learned/lstm.h>

namespace odotune::learned {

namespace lstm_bptt_detail {

// What the forward pass keeps for the backward one, in one thread_local
// buffer per <I, H> (about window × 7H doubles).
struct Tape {
  double* gates;  // window × 4H: i, f, g, o after activation
  double* cs;     // (window + 1) × H, cs[0..H) = c_0 = 0
  double* hs;     // (window + 1) × H, hs[0..H) = h_0 = 0
  double* tcs;    // window × H: tanh(c_t)
};

template <int I, int H>
Tape tape_for(int window) {
  constexpr int G = LstmLayout<I, H>::kGates;
  thread_local std::vector<double> buffer;
  const std::size_t need = static_cast<std::size_t>(window) * (G + H) +
                           static_cast<std::size_t>(window + 1) * 2 * H;
  if (buffer.size() < need) buffer.resize(need);
  Tape tape;
  tape.gates = buffer.data();
  tape.cs = tape.gates + static_cast<std::size_t>(window) * G;
  tape.hs = tape.cs + static_cast<std::size_t>(window + 1) * H;
  tape.tcs = tape.hs + static_cast<std::size_t>(window + 1) * H;
  return tape;
}

// The forward recursion over the window (odotune/learned/lstm.h), recorded on the tape.
template <int I, int H>
void forward(const double* w, const double* x, int window, const Tape& tape) {
  using L = LstmLayout<I, H>;
  constexpr int G = L::kGates;
  for (int j = 0; j < H; ++j) tape.cs[j] = tape.hs[j] = 0.0;
  std::array<double, G> z;
  for (int t = 0; t < window; ++t) {
    const double* xt = x + static_cast<std::size_t>(t) * I;
    const double* h_prev = tape.hs + static_cast<std::size_t>(t) * H;
    const double* c_prev = tape.cs + static_cast<std::size_t>(t) * H;
    double* g_t = tape.gates + static_cast<std::size_t>(t) * G;
    double* c_t = tape.cs + static_cast<std::size_t>(t + 1) * H;
    double* h_t = tape.hs + static_cast<std::size_t>(t + 1) * H;
    double* tc_t = tape.tcs + static_cast<std::size_t>(t) * H;
    for (int n = 0; n < G; ++n) z[n] = w[L::kBias + n];
    for (int k = 0; k < I; ++k) {
      const double* wk = w + L::kKernel + k * G;
      for (int n = 0; n < G; ++n) z[n] += wk[n] * xt[k];
    }
    for (int m = 0; m < H; ++m) {
      const double* um = w + L::kRecurrent + m * G;
      const double hm = h_prev[m];
      for (int n = 0; n < G; ++n) z[n] += um[n] * hm;
    }
    for (int j = 0; j < H; ++j) {
      const double i_gate = lstm_detail::sigmoid(z[j]);
      const double f_gate = lstm_detail::sigmoid(z[H + j]);
      const double g_cand = lstm_detail::tanh_exp(z[2 * H + j]);
      const double o_gate = lstm_detail::sigmoid(z[3 * H + j]);
      g_t[j] = i_gate;
      g_t[H + j] = f_gate;
      g_t[2 * H + j] = g_cand;
      g_t[3 * H + j] = o_gate;
      c_t[j] = f_gate * c_prev[j] + i_gate * g_cand;
      const double tanh_c = lstm_detail::tanh_exp(c_t[j]);
      tc_t[j] = tanh_c;
      h_t[j] = o_gate * tanh_c;
    }
  }
}

// The backward recursion (file comment) from δh_T = d, accumulated into grad.
template <int I, int H>
void backward(const double* w, const double* x, int window, const Tape& tape, double* grad) {
  using L = LstmLayout<I, H>;
  constexpr int G = L::kGates;
  std::array<double, H> dh, dc, dh_prev;
  for (int j = 0; j < H; ++j) {
    dh[j] = w[L::kDense + j];
    dc[j] = 0.0;
  }
  std::array<double, G> dz;
  for (int t = window - 1; t >= 0; --t) {
    const double* xt = x + static_cast<std::size_t>(t) * I;
    const double* g_t = tape.gates + static_cast<std::size_t>(t) * G;
    const double* tc_t = tape.tcs + static_cast<std::size_t>(t) * H;
    const double* c_prev = tape.cs + static_cast<std::size_t>(t) * H;
    const double* h_prev = tape.hs + static_cast<std::size_t>(t) * H;
    for (int j = 0; j < H; ++j) {
      const double i_gate = g_t[j], f_gate = g_t[H + j], g_cand = g_t[2 * H + j], o_gate = g_t[3 * H + j];
      const double tc = tc_t[j];
      const double dcj = dc[j] + dh[j] * o_gate * (1.0 - tc * tc);
      dz[j] = dcj * g_cand * i_gate * (1.0 - i_gate);
      dz[H + j] = dcj * c_prev[j] * f_gate * (1.0 - f_gate);
      dz[2 * H + j] = dcj * i_gate * (1.0 - g_cand * g_cand);
      dz[3 * H + j] = dh[j] * tc * o_gate * (1.0 - o_gate);
      dc[j] = dcj * f_gate;
    }
    for (int n = 0; n < G; ++n) grad[L::kBias + n] += dz[n];
    for (int k = 0; k < I; ++k) {
      double* gk = grad + L::kKernel + k * G;
      for (int n = 0; n < G; ++n) gk[n] += xt[k] * dz[n];
    }
    for (int m = 0; m < H; ++m) {
      double* gm = grad + L::kRecurrent + m * G;
      const double* um = w + L::kRecurrent + m * G;
      double acc = 0.0;
      for (int n = 0; n < G; ++n) {
        gm[n] += h_prev[m] * dz[n];
        acc += um[n] * dz[n];
      }
      dh_prev[m] = acc;
    }
    dh = dh_prev;
  }
}

}  // namespace lstm_bptt_detail

// Returns lstm_forward<I, H, double>(w, x, window, act) (the same operations
// in the same order, so the same value) and, when grad != nullptr, writes
// d output / d w into grad[0 .. kCount). Not allocating after the first call
// on a thread (one thread_local buffer of about window × 7H doubles).
template <int I, int H>
double lstm_value_and_gradient(const double* w, const double* x, int window, OutputActivation act,
                               double* grad) {
  using L = LstmLayout<I, H>;
  const lstm_bptt_detail::Tape tape = lstm_bptt_detail::tape_for<I, H>(window);
  lstm_bptt_detail::forward<I, H>(w, x, window, tape);
  const double* h_last = tape.hs + static_cast<std::size_t>(window) * H;
  double out = w[L::kDenseBias];
  for (int j = 0; j < H; ++j) out += w[L::kDense + j] * h_last[j];
  const bool floored = act == OutputActivation::relu && out < 0.0;
  if (grad == nullptr) return floored ? 0.0 : out;
  for (int n = 0; n < L::kCount; ++n) grad[n] = 0.0;
  if (floored) return 0.0;

  for (int j = 0; j < H; ++j) grad[L::kDense + j] = h_last[j];
  grad[L::kDenseBias] = 1.0;
  lstm_bptt_detail::backward<I, H>(w, x, window, tape, grad);
  return out;
}

}  // namespace odotune::learned
