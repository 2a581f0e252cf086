// Training of the LSTM nets (odotune/learned/lstm.h) with Ceres.
//
// Fariña et al., "Improving Odometric Model Performance Based on LSTM
// Networks", Sensors 2023, 23, 961, train with ADAM on the MAE (§4, §4.1) and
// retrain online on 300 fresh samples (§4.2). Here the same objective is
// minimised by Ceres' trust-region Levenberg–Marquardt, one residual block
// per window:
//   r_n(w) = net_w(z_n) − ỹ_n,   cost = ½ Σ_n ρ(r_n²)   (+ ½·λ·‖w − w̄‖² if weight_decay λ > 0;
//   w̄ = 0, or the starting weights with decay_to_start)
// with z_n the standardised window (eq. 4), ỹ_n = (y_n − output_mean)/output_sd
// and ρ = ceres::SoftLOneLoss(a): ρ(s) = 2a²(√(1 + s/a²) − 1) ≈ 2a|r| for
// |r| ≫ a, i.e. the MAE up to a constant factor, smooth near 0 so that LM's
// Gauss–Newton model exists. Where |r| ≫ a that model is nearly flat (the MAE
// has no curvature) and LM barely moves, so the scale is annealed: a starts
// at LstmTrainingOptions::mae_scale_start and is divided by 10 per Ceres
// solve down to mae_scale (measured: with a = 0.05 from the start, 60
// iterations on a 350-window memory task left the validation MAE at the
// constant predictor's; annealed from 1, 40 iterations reached ~1/8 of it).
//
// Jacobians: LstmResidual is the plain templated functor for
// ceres::AutoDiffCostFunction ("automatic differentiation through the
// unrolled window"; forward mode, ≈ kCount forward passes per row) and
// LstmBpttCost the same residual with its Jacobian row by backpropagation
// through time (odotune/learned/lstm_bptt.h, ≈ 3 forward passes). Options select
// which one trains; tests check both against each other and against finite
// differences.
//
// Determinism: Ceres itself runs single-threaded (its multi-threaded
// evaluator sums the cost in thread-dependent order); `num_threads` instead
// parallelises the evaluation of all windows inside a ceres::EvaluationCallback,
// each window written to its own slot, so the weights are bit-identical for
// any thread count.
#pragma once

#include <ceres/ceres.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <odotune/learned/lstm.h>
#include <odotune/learned/lstm_bptt.h>

namespace odotune::learned {

// Windows of raw samples and their raw targets.
struct SequenceSet {
  int window = 20, inputs = 3;
  std::vector<double> x;  // size() × window × inputs, raw, row-major (window n, sample t oldest first, input k)
  std::vector<double> y;  // size() raw targets
  std::size_t size() const { return y.size(); }
  // Appends one window: window × inputs values of window_rows, and its target.
  void add(const double* window_rows, double target) {
    x.insert(x.end(), window_rows,
             window_rows + static_cast<std::size_t>(window) * static_cast<std::size_t>(inputs));
    y.push_back(target);
  }
  // Appends every window of `other` (same window and inputs).
  void append(const SequenceSet& other) {
    x.insert(x.end(), other.x.begin(), other.x.end());
    y.insert(y.end(), other.y.begin(), other.y.end());
  }
  // Pointer to window n's first value.
  const double* window_data(std::size_t n) const {
    return x.data() + n * static_cast<std::size_t>(window) * static_cast<std::size_t>(inputs);
  }
  // Consistent dimensions (window ≥ 1, inputs ≥ 1, x.size() = size()·window·inputs)
  // and finite values; `why` names the bad field or window.
  bool IsValid(std::string* why) const;
};

// First `fraction` of the windows (chronological, no shuffling; count rounded
// to nearest) and the rest: the paper's 70/30 split (§4). Throws
// std::invalid_argument for fraction outside [0, 1] or an inconsistent set.
std::pair<SequenceSet, SequenceSet> split_sequences(const SequenceSet& all, double fraction = 0.7);

struct LstmTrainingOptions {
  enum class Jacobian { bptt, autodiff };
  Jacobian jacobian = Jacobian::bptt;
  int max_iterations = 100;  // Ceres iterations (≥ 0)
  double mae_scale =
      0.05;  // robust-loss scale a, in standardised target units (ceres::SoftLOneLoss: ≈ |r| for |r| ≫ a → MAE)
  // Continuation (graduated loss): Levenberg–Marquardt's Gauss–Newton model
  // of ρ is nearly flat where |r| ≫ a (Ceres' robust-loss correction; the
  // MAE has no curvature), so training starts at this larger scale and
  // divides it by 10 per Ceres solve down to mae_scale (≤ mae_scale: one
  // solve). max_iterations is shared among the solves.
  double mae_scale_start = 1.0;
  double function_tolerance = 1e-7;  // Ceres Solver::Options::function_tolerance (≥ 0)
  double weight_decay = 0.0;         // optional L2 λ on the weights (one extra residual block), 0 = off
  // The decay pulls toward the starting weights instead of 0: for
  // retraining, a Gaussian prior centred on the current model (MAP), so that
  // a few hundred noisy samples move the weights only as far as they
  // disagree with it ("elastic" refits; cf. Kirkpatrick et al., PNAS 2017,
  // with an isotropic weight).
  bool decay_to_start = false;
  // Fresh training starts with the dense output's weights and bias at 0 and
  // output_mean 0, so the untrained net outputs exactly 0: a net that learns
  // a correction to a base model and knows nothing leaves the base unchanged
  // (with decay_to_start, the decay pulls toward that).
  bool zero_output_start = false;
  std::uint64_t seed =
      1;  // initial weights (Glorot-uniform from odotune/core/counter_rng.h: thread-count independent)
  int num_threads = 1;  // OpenMP threads evaluating the windows (≥ 1); results do not depend on it
  // Early stopping (train_lstm with a validation set): when > 0, the
  // validation MAE is taken after every iteration, the weights with the
  // smallest are kept, and training stops once this many iterations in a
  // row of the last continuation stage have not improved on it (the coarse
  // stages before it can sit on a plateau first). 0: off, the last iterate
  // is kept.
  int early_stopping_patience = 0;
  // > 0: stop once this many iterations have run in all (of the
  // max_iterations the continuation stages share as usual; counted as early
  // stopping counts them, a solve's start not included), to repeat an
  // early-stopped run's length on more data. 0: off.
  int stop_after_iterations = 0;
  bool IsValid(std::string* why) const;
};

struct LstmTrainingSummary {
  std::string termination;                  // Ceres termination type + message
  int iterations = 0;                       // Ceres iterations (successful + unsuccessful steps, all stages)
  double initial_cost = 0, final_cost = 0;  // ½ Σ ρ(r²) at mae_scale (+ decay), standardised units
  double train_mae = 0, validation_mae = std::numeric_limits<double>::quiet_NaN();  // raw target units
  double seconds = 0;                                                               // wall time of the solve
  bool usable = false;  // finite weights and the solver did not fail
  // Early stopping: the validation MAE before training and after each
  // iteration [raw units], and the iteration whose weights were kept (0: the
  // start); empty and −1 without it.
  std::vector<double> validation_curve;
  int best_iteration = -1;
};

// Residual r = net(z) − ỹ of one standardised window z (window × I) with
// standardised target ỹ: the plain templated functor for
// ceres::AutoDiffCostFunction<LstmResidual<I, H>, 1, LstmLayout<I, H>::kCount>.
// Does not own x.
template <int I, int H>
struct LstmResidual {
  const double* x = nullptr;
  int window = 0;
  double target = 0.0;
  OutputActivation activation = OutputActivation::linear;
  template <typename T>
  bool operator()(const T* weights, T* residual) const {
    residual[0] = lstm_forward<I, H, T>(weights, x, window, activation) - T(target);
    return true;
  }
};

// The same residual with its Jacobian row by backpropagation through time
// (odotune/learned/lstm_bptt.h explains why hand-written). Returns false (an
// evaluation failure Ceres handles) on a non-finite residual or Jacobian;
// never throws. Does not own x.
template <int I, int H>
class LstmBpttCost final : public ceres::SizedCostFunction<1, LstmLayout<I, H>::kCount> {
 public:
  LstmBpttCost(const double* x, int window, double target, OutputActivation activation)
      : x_(x), window_(window), target_(target), activation_(activation) {}
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    double* row = (jacobians != nullptr) ? jacobians[0] : nullptr;
    residuals[0] = lstm_value_and_gradient<I, H>(parameters[0], x_, window_, activation_, row) - target_;
    if (!std::isfinite(residuals[0])) return false;
    if (row != nullptr)
      for (int n = 0; n < LstmLayout<I, H>::kCount; ++n)
        if (!std::isfinite(row[n])) return false;
    return true;
  }

 private:
  const double* x_;
  int window_;
  double target_;
  OutputActivation activation_;
};

// Seeded Glorot-uniform initial weights (Keras' defaults, except the
// recurrent kernel, Glorot instead of orthogonal): W ~ U(±√(6/(I + 4H))),
// U ~ U(±√(6/(H + 4H))), d ~ U(±√(6/(H + 1))), biases 0 except the forget
// gate's 1 (Keras unit_forget_bias). Same seed ⇒ same weights.
template <int I, int H>
std::array<double, LstmLayout<I, H>::kCount> lstm_initial_weights(std::uint64_t seed);

// Fresh training: standardisation from `train` (inputs and, for linear output,
// target mean/sd; for ReLU output, output_mean = min of the targets and
// output_sd = their sd, so the ReLU's 0 is the floor; a zero sd becomes 1),
// net.window = train.window, seeded initial weights, then LM as above.
// net.activation is kept. The net is changed only when the summary is usable.
// `validation` may be empty, of any shape (validation_mae NaN). Throws std::invalid_argument
// (one line) for invalid options, an empty or invalid train set, or sets
// whose inputs ≠ I or whose windows differ.
template <int I, int H>
LstmTrainingSummary train_lstm(LstmNet<I, H>& net, const SequenceSet& train, const SequenceSet& validation,
                               const LstmTrainingOptions& options);

// Retraining (paper §4.2): keeps the net's standardisation and window and
// starts from its current weights (options.seed unused). The net is changed
// only when the summary is usable. Throws std::invalid_argument as train_lstm,
// and for an invalid net or train.window ≠ net.window.
template <int I, int H>
LstmTrainingSummary retrain_lstm(LstmNet<I, H>& net, const SequenceSet& train,
                                 const LstmTrainingOptions& options);

// Mean |net.predict(x_n) − y_n| over the set, raw units (NaN when empty).
// Requires net.IsValid() and matching dimensions (throws std::invalid_argument).
template <int I, int H>
double lstm_mae(const LstmNet<I, H>& net, const SequenceSet& set);

}  // namespace odotune::learned
