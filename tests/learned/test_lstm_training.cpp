// LSTM training (odotune/learned/lstm_training.h, lstm_bptt.h): BPTT Jacobian vs
// Ceres autodiff vs central finite differences, training lowers the MAE on a
// task that needs memory, retraining adapts, thread-count determinism,
// split_sequences and the bad-input messages.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include <odotune/core/counter_rng.h>
#include <odotune/learned/lstm_training.h>

namespace odotune::learned {
namespace {

double draw(std::uint64_t seed, std::uint64_t n, double lo, double hi) {
  return lo + (hi - lo) * core::counter_uniform01(seed, 3, n, 0, 4242);
}

// ---------------------------------------------------------------- gradients

template <int I, int H>
struct GradientCase {
  static constexpr int K = LstmLayout<I, H>::kCount;
  std::vector<double> w = std::vector<double>(K);
  std::vector<double> x;
  int window = 20;
  double target = 0.3;
  GradientCase(std::uint64_t seed, int win) : window(win) {
    for (int n = 0; n < K; ++n) w[n] = draw(seed, static_cast<std::uint64_t>(n), -0.7, 0.7);
    x.resize(static_cast<std::size_t>(window * I));
    for (std::size_t n = 0; n < x.size(); ++n) x[n] = draw(seed + 77, n, -2.0, 2.0);
  }
  // Shifts the dense bias so that the linear output equals `value`.
  void set_output(double value) {
    const double out = lstm_forward<I, H, double>(w.data(), x.data(), window, OutputActivation::linear);
    w[LstmLayout<I, H>::kDenseBias] += value - out;
  }
};

template <int I, int H>
void check_gradients(std::uint64_t seed, OutputActivation act, double output) {
  constexpr int K = LstmLayout<I, H>::kCount;
  GradientCase<I, H> c(seed, 20);
  c.set_output(output);
  LstmBpttCost<I, H> bptt(c.x.data(), c.window, c.target, act);
  ceres::AutoDiffCostFunction<LstmResidual<I, H>, 1, K> autodiff(new LstmResidual<I, H>{c.x.data(), c.window,
                                                                                        c.target, act});

  const double* params[1] = {c.w.data()};
  double r_bptt = 0.0, r_auto = 0.0;
  std::vector<double> j_bptt(K), j_auto(K);
  double* jb[1] = {j_bptt.data()};
  double* ja[1] = {j_auto.data()};
  ASSERT_TRUE(bptt.Evaluate(params, &r_bptt, jb));
  ASSERT_TRUE(autodiff.Evaluate(params, &r_auto, ja));
  const double expected_r = (act == OutputActivation::relu ? std::max(0.0, output) : output) - c.target;
  EXPECT_NEAR(r_bptt, expected_r, 1e-12);
  EXPECT_NEAR(r_auto, expected_r, 1e-12);

  double scale = 0.0;
  for (int n = 0; n < K; ++n) scale = std::max(scale, std::abs(j_auto[n]));
  if (act == OutputActivation::relu && output < 0.0) {
    EXPECT_EQ(scale, 0.0);
    for (int n = 0; n < K; ++n) EXPECT_EQ(j_bptt[n], 0.0) << n;
    return;
  }
  ASSERT_GT(scale, 0.0);
  // Central differences, step h: truncation O(h²), rounding O(ε/h).
  const double h = 1e-6;
  int checked_nonzero = 0;
  for (int n = 0; n < K; ++n) {
    ASSERT_NEAR(j_bptt[n], j_auto[n], 1e-10 * scale) << "weight " << n;
    std::vector<double> wp = c.w, wm = c.w;
    wp[n] += h;
    wm[n] -= h;
    const double fp = lstm_forward<I, H, double>(wp.data(), c.x.data(), c.window, act);
    const double fm = lstm_forward<I, H, double>(wm.data(), c.x.data(), c.window, act);
    const double fd = (fp - fm) / (2.0 * h);
    ASSERT_NEAR(j_bptt[n], fd, 1e-6 * scale) << "weight " << n;
    if (std::abs(fd) > 1e-3 * scale) ++checked_nonzero;
  }
  // The check is not vacuous: most weights (all four gates, W, U, b, d) matter.
  EXPECT_GT(checked_nonzero, K / 2);
}

TEST(LstmGradient, BpttEqualsAutodiffAndFiniteDifferences_3_5) {
  check_gradients<3, 5>(1, OutputActivation::linear, 0.8);
  check_gradients<3, 5>(2, OutputActivation::linear, -0.4);
  check_gradients<3, 5>(3, OutputActivation::relu, 0.5);   // active region
  check_gradients<3, 5>(4, OutputActivation::relu, -0.5);  // floored: zero row
}

TEST(LstmGradient, BpttEqualsAutodiffAndFiniteDifferences_5_10) {
  check_gradients<5, 10>(5, OutputActivation::linear, 0.2);
  check_gradients<5, 10>(6, OutputActivation::relu, 0.9);
}

TEST(LstmGradient, ValueOnlyEvaluationMatchesForward) {
  GradientCase<3, 5> c(9, 7);
  LstmBpttCost<3, 5> bptt(c.x.data(), c.window, c.target, OutputActivation::linear);
  const double* params[1] = {c.w.data()};
  double r = 0.0;
  ASSERT_TRUE(bptt.Evaluate(params, &r, nullptr));
  EXPECT_EQ(r + c.target,
            (lstm_forward<3, 5, double>(c.w.data(), c.x.data(), c.window, OutputActivation::linear)));
}

// -------------------------------------------------------- a memory task

// A raw input sequence u (3 features with offsets/scales, so standardisation
// matters) and windows of 20 whose target depends on the last three samples
// non-linearly: y_t = tanh(0.9 a_t + 0.6 a_{t−1} − 0.5 b_{t−2}), with a, b
// (and the distractor c) the features standardised by construction.
SequenceSet memory_task(std::uint64_t seed, int windows, double gain = 1.0, double offset = 0.0) {
  SequenceSet set;
  set.window = 20;
  set.inputs = 3;
  const int length = windows + set.window - 1;
  std::vector<double> a(length), b(length), c(length), raw(static_cast<std::size_t>(length) * 3);
  for (int t = 0; t < length; ++t) {
    a[t] = draw(seed, static_cast<std::uint64_t>(3 * t), -1.0, 1.0);
    b[t] = draw(seed, static_cast<std::uint64_t>(3 * t + 1), -1.0, 1.0);
    c[t] = draw(seed, static_cast<std::uint64_t>(3 * t + 2), -1.0, 1.0);
    raw[3 * t] = 50.0 + 10.0 * a[t];
    raw[3 * t + 1] = -0.02 + 0.01 * b[t];
    raw[3 * t + 2] = c[t];
  }
  for (int n = 0; n < windows; ++n) {
    const int t = n + set.window - 1;  // last sample of the window
    const double y = std::tanh(0.9 * a[t] + 0.6 * a[t - 1] - 0.5 * b[t - 2]);
    set.add(raw.data() + 3 * n, gain * y + offset);
  }
  return set;
}

double constant_predictor_mae(const SequenceSet& train, const SequenceSet& test) {
  std::vector<double> y = train.y;
  std::nth_element(y.begin(), y.begin() + static_cast<std::ptrdiff_t>(y.size() / 2), y.end());
  const double median = y[y.size() / 2];  // the MAE-optimal constant
  double sum = 0.0;
  for (double v : test.y) sum += std::abs(v - median);
  return sum / static_cast<double>(test.size());
}

TEST(LstmTraining, LowersMaeOnAMemoryTask) {
  const auto [train, validation] = split_sequences(memory_task(17, 500), 0.7);
  ASSERT_EQ(train.size(), 350u);
  LstmTrainingOptions options;
  options.max_iterations = 0;
  VelocityNet initial;
  const auto s0 = train_lstm(initial, train, validation, options);
  ASSERT_TRUE(s0.usable) << s0.termination;

  options.max_iterations = 40;
  VelocityNet net;
  const auto s = train_lstm(net, train, validation, options);
  ASSERT_TRUE(s.usable) << s.termination;
  const double constant = constant_predictor_mae(train, validation);
  EXPECT_LT(s.final_cost, 0.5 * s.initial_cost);
  EXPECT_LT(s.validation_mae, 0.4 * constant) << "constant predictor " << constant;
  EXPECT_LT(s.validation_mae, 0.4 * s0.validation_mae) << "initial net " << s0.validation_mae;
  EXPECT_NEAR(s.validation_mae, lstm_mae(net, validation), 1e-12);
  EXPECT_NEAR(s.train_mae, lstm_mae(net, train), 1e-12);
  EXPECT_GT(s.iterations, 0);
  EXPECT_FALSE(s.termination.empty());
  // Standardisation from the train set (eq. 4): feature 0 is 50 + 10·U(−1, 1).
  EXPECT_NEAR(net.input_mean[0], 50.0, 1.5);
  EXPECT_NEAR(net.input_sd[0], 10.0 / std::sqrt(3.0), 0.6);
  EXPECT_EQ(net.window, 20);
}

// Early stopping keeps the weights of the iteration with the smallest
// validation MAE (its curve is recorded, the kept net's MAE is its minimum);
// a run stopped after that many iterations on the same data ends there.
TEST(LstmTraining, EarlyStoppingKeepsTheBestValidationIterate) {
  // Few training windows against many validation ones, so that the fit
  // overtakes the validation optimum within the budget.
  const SequenceSet train = memory_task(41, 60);
  const SequenceSet validation = memory_task(42, 300);
  LstmTrainingOptions o;
  o.max_iterations = 60;
  o.early_stopping_patience = 4;
  VelocityNet net;
  const auto s = train_lstm(net, train, validation, o);
  ASSERT_TRUE(s.usable) << s.termination;
  ASSERT_GE(s.validation_curve.size(), 2u);
  ASSERT_GE(s.best_iteration, 0);
  ASSERT_LT(static_cast<std::size_t>(s.best_iteration), s.validation_curve.size());
  const double best = *std::min_element(s.validation_curve.begin(), s.validation_curve.end());
  EXPECT_EQ(s.validation_curve[static_cast<std::size_t>(s.best_iteration)], best);
  EXPECT_NEAR(lstm_mae(net, validation), best, 1e-12);
  EXPECT_LE(static_cast<int>(s.validation_curve.size()) - 1, o.max_iterations);
  // Without early stopping: no curve, the last iterate.
  o.early_stopping_patience = 0;
  VelocityNet plain;
  const auto p = train_lstm(plain, train, validation, o);
  EXPECT_TRUE(p.validation_curve.empty());
  EXPECT_EQ(p.best_iteration, -1);
  // Stopped after a given number of iterations (the curve counts them; the
  // patience never ends this run).
  o.stop_after_iterations = 7;
  o.early_stopping_patience = 1000;
  VelocityNet short_run;
  const auto q = train_lstm(short_run, train, validation, o);
  EXPECT_EQ(q.validation_curve.size(), 8u);
  o.stop_after_iterations = -1;
  EXPECT_THROW(train_lstm(short_run, train, validation, o), std::invalid_argument);
}

TEST(LstmTraining, RetrainingAdaptsToShiftedTargets) {
  const SequenceSet train = memory_task(31, 300);
  LstmTrainingOptions options;
  options.max_iterations = 40;
  VelocityNet net;
  ASSERT_TRUE(train_lstm(net, train, SequenceSet{}, options).usable);

  // The robot changed: targets scaled (e.g. a tyre pressure change, paper §4.2).
  const SequenceSet shifted = memory_task(32, 300, 0.9, 0.1);
  const SequenceSet shifted_test = memory_task(33, 200, 0.9, 0.1);
  const double before = lstm_mae(net, shifted);
  const double before_test = lstm_mae(net, shifted_test);
  const auto mean_before = net.input_mean;
  options.max_iterations = 15;
  VelocityNet retrained = net;
  const auto s = retrain_lstm(retrained, shifted, options);
  ASSERT_TRUE(s.usable) << s.termination;
  EXPECT_LT(s.train_mae, 0.8 * before);
  EXPECT_LT(lstm_mae(retrained, shifted_test), before_test);
  EXPECT_EQ(retrained.input_mean, mean_before);  // standardisation kept
  EXPECT_EQ(retrained.output_mean, net.output_mean);
}

TEST(LstmTraining, SameSeedSameWeightsForAnyThreadCount) {
  const SequenceSet train = memory_task(41, 150);
  LstmTrainingOptions options;
  options.max_iterations = 10;
  VelocityNet one, two, again;
  options.num_threads = 1;
  const auto s1 = train_lstm(one, train, SequenceSet{}, options);
  const auto s3 = train_lstm(again, train, SequenceSet{}, options);
  options.num_threads = 2;
  const auto s2 = train_lstm(two, train, SequenceSet{}, options);
  ASSERT_TRUE(s1.usable && s2.usable);
  EXPECT_EQ(0, std::memcmp(one.weights.data(), two.weights.data(), sizeof(one.weights)));
  EXPECT_EQ(0, std::memcmp(one.weights.data(), again.weights.data(), sizeof(one.weights)));
  EXPECT_EQ(s1.final_cost, s2.final_cost);
  EXPECT_EQ(s1.iterations, s2.iterations);
  EXPECT_EQ(s1.final_cost, s3.final_cost);
  // A different seed starts elsewhere.
  options.seed = 2;
  VelocityNet other;
  train_lstm(other, train, SequenceSet{}, options);
  EXPECT_NE(0, std::memcmp(one.weights.data(), other.weights.data(), sizeof(one.weights)));
}

TEST(LstmTraining, AutodiffAndBpttTrainTheSameWay) {
  // Few windows for the slow forward-mode path; a little weight decay keeps
  // the (under-determined) problem well conditioned, so that Jacobians equal
  // to ~1e-13 give weights equal to ~1e-9.
  const SequenceSet train = memory_task(51, 40);
  LstmTrainingOptions options;
  options.max_iterations = 9;
  options.weight_decay = 0.01;
  VelocityNet a, b;
  options.jacobian = LstmTrainingOptions::Jacobian::bptt;
  const auto sa = train_lstm(a, train, SequenceSet{}, options);
  options.jacobian = LstmTrainingOptions::Jacobian::autodiff;
  options.num_threads = 2;
  const auto sb = train_lstm(b, train, SequenceSet{}, options);
  ASSERT_TRUE(sa.usable && sb.usable);
  EXPECT_LT(sa.final_cost, sa.initial_cost);
  EXPECT_NEAR(sa.final_cost, sb.final_cost, 1e-8 * sa.initial_cost);
  for (int n = 0; n < VelocityNet::kWeights; ++n)
    EXPECT_NEAR(a.weights[n], b.weights[n], 1e-7 * (1.0 + std::abs(a.weights[n]))) << n;
}

TEST(LstmTraining, SlipNetReluFloorIsTheTargetMinimum) {
  // Detector-shaped data: 5 inputs, a non-negative "variance" target that
  // jumps when wheel power and encoder increment disagree.
  SequenceSet set;
  set.window = 20;
  set.inputs = 5;
  const int windows = 80, length = windows + 19;
  std::vector<double> raw(static_cast<std::size_t>(length) * 5);
  for (int t = 0; t < length; ++t)
    for (int k = 0; k < 5; ++k) raw[5 * t + k] = draw(61, static_cast<std::uint64_t>(5 * t + k), 0.0, 1.0);
  for (int n = 0; n < windows; ++n) {
    const double* last = raw.data() + 5 * (n + 19);
    const double slip = std::abs(last[0] - last[2]) + std::abs(last[1] - last[3]);
    set.add(raw.data() + 5 * n, 0.01 + (slip > 0.8 ? 0.5 * slip : 0.0));
  }
  SlipNet net;
  net.activation = OutputActivation::relu;
  LstmTrainingOptions options;
  options.max_iterations = 0;
  SlipNet initial = net;
  const auto s0 = train_lstm(initial, set, SequenceSet{}, options);
  options.max_iterations = 8;
  const auto s = train_lstm(net, set, SequenceSet{}, options);
  ASSERT_TRUE(s.usable) << s.termination;
  EXPECT_EQ(net.output_mean, *std::min_element(set.y.begin(), set.y.end()));
  EXPECT_LT(s.train_mae, s0.train_mae);
  for (std::size_t n = 0; n < set.size(); ++n) EXPECT_GE(net.predict(set.window_data(n)), net.output_mean);
}

// ------------------------------------------------------------- split, errors

TEST(SplitSequences, ChronologicalSplit) {
  SequenceSet all;
  all.window = 2;
  all.inputs = 1;
  for (int n = 0; n < 10; ++n) {
    const double rows[2] = {1.0 * n, 1.0 * n + 0.5};
    all.add(rows, 100.0 + n);
  }
  const auto [first, rest] = split_sequences(all);
  ASSERT_EQ(first.size(), 7u);
  ASSERT_EQ(rest.size(), 3u);
  EXPECT_EQ(first.y.front(), 100.0);
  EXPECT_EQ(first.y.back(), 106.0);
  EXPECT_EQ(rest.y.front(), 107.0);
  EXPECT_EQ(rest.x, (std::vector<double>{7.0, 7.5, 8.0, 8.5, 9.0, 9.5}));
  EXPECT_EQ(first.x.size(), 14u);
  EXPECT_EQ(rest.window, 2);
  EXPECT_EQ(split_sequences(all, 1.0).second.size(), 0u);
  EXPECT_EQ(split_sequences(all, 0.0).first.size(), 0u);
  EXPECT_EQ(split_sequences(all, 0.25).first.size(), 3u);  // 2.5 rounds away from zero
  EXPECT_THROW(split_sequences(all, 1.5), std::invalid_argument);
}

template <typename F>
std::string message_of(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
    return what;
  }
  ADD_FAILURE() << "no std::invalid_argument thrown";
  return {};
}

TEST(LstmTraining, BadInputNamesTheField) {
  const SequenceSet good = memory_task(71, 5);
  LstmTrainingOptions options;
  options.max_iterations = 1;
  VelocityNet net;
  auto contains = [](const std::string& s, const std::string& part) {
    return s.find(part) != std::string::npos;
  };

  EXPECT_TRUE(contains(message_of([&] { train_lstm(net, SequenceSet{}, SequenceSet{}, options); }), "empty"));
  SequenceSet wrong_inputs;
  wrong_inputs.inputs = 4;
  std::vector<double> rows(80, 0.0);
  wrong_inputs.add(rows.data(), 1.0);
  EXPECT_TRUE(contains(message_of([&] { train_lstm(net, wrong_inputs, SequenceSet{}, options); }),
                       "inputs = 4"));
  SequenceSet short_x = good;
  short_x.x.pop_back();
  EXPECT_TRUE(contains(message_of([&] { train_lstm(net, short_x, SequenceSet{}, options); }), "x has"));
  SequenceSet nan_y = good;
  nan_y.y[3] = std::nan("");
  EXPECT_TRUE(contains(message_of([&] { train_lstm(net, nan_y, SequenceSet{}, options); }), "y[3]"));
  SequenceSet other_window;
  other_window.window = 10;
  other_window.add(rows.data(), 0.0);
  EXPECT_TRUE(contains(message_of([&] { train_lstm(net, good, other_window, options); }),
                       "validation set: window"));

  LstmTrainingOptions bad = options;
  bad.mae_scale = 0.0;
  EXPECT_TRUE(contains(message_of([&] { train_lstm(net, good, SequenceSet{}, bad); }), "mae_scale"));
  bad = options;
  bad.num_threads = 0;
  EXPECT_TRUE(contains(message_of([&] { retrain_lstm(net, good, bad); }), "num_threads"));
  bad = options;
  bad.weight_decay = -1.0;
  EXPECT_TRUE(contains(message_of([&] { train_lstm(net, good, SequenceSet{}, bad); }), "weight_decay"));

  VelocityNet ten = net;
  ten.window = 10;
  EXPECT_TRUE(contains(message_of([&] { retrain_lstm(ten, good, options); }), "expected the net's 10"));
  VelocityNet broken = net;
  broken.output_sd = 0.0;
  EXPECT_TRUE(contains(message_of([&] { retrain_lstm(broken, good, options); }), "output_sd"));
}

TEST(LstmTraining, WeightDecayShrinksWeights) {
  const SequenceSet train = memory_task(81, 120);
  LstmTrainingOptions options;
  options.max_iterations = 15;
  VelocityNet plain, decayed;
  ASSERT_TRUE(train_lstm(plain, train, SequenceSet{}, options).usable);
  options.weight_decay = 5.0;
  ASSERT_TRUE(train_lstm(decayed, train, SequenceSet{}, options).usable);
  double n_plain = 0.0, n_decayed = 0.0;
  for (int n = 0; n < VelocityNet::kWeights; ++n) {
    n_plain += plain.weights[n] * plain.weights[n];
    n_decayed += decayed.weights[n] * decayed.weights[n];
  }
  EXPECT_LT(n_decayed, n_plain);
}

// Refit settings like the fusion's (learned_fusion.h): final loss scale, 10 iterations.
LstmTrainingOptions default_options_for_refit() {
  LstmTrainingOptions o;
  o.max_iterations = 10;
  o.mae_scale_start = o.mae_scale;
  return o;
}

TEST(LstmTraining, DecayToStartKeepsARefitNearTheCurrentWeights) {
  // A refit on a few noisy samples of a shifted task: decay toward the
  // starting weights (the retraining prior) moves the weights less than a
  // free refit, and less than decay of the same λ toward zero; it still
  // lowers the training cost from where it started.
  const SequenceSet train = memory_task(41, 300);
  LstmTrainingOptions options;
  options.max_iterations = 40;
  VelocityNet net;
  ASSERT_TRUE(train_lstm(net, train, SequenceSet{}, options).usable);
  const SequenceSet few = memory_task(42, 40, 0.9, 0.1);
  auto moved = [&](double lambda, bool to_start, LstmTrainingSummary* summary) {
    LstmTrainingOptions o = default_options_for_refit();
    o.weight_decay = lambda;
    o.decay_to_start = to_start;
    VelocityNet refit = net;
    *summary = retrain_lstm(refit, few, o);
    double d2 = 0.0;
    for (int n = 0; n < VelocityNet::kWeights; ++n)
      d2 += (refit.weights[n] - net.weights[n]) * (refit.weights[n] - net.weights[n]);
    return std::sqrt(d2);
  };
  LstmTrainingSummary free_s, start_s, zero_s;
  const double free_move = moved(0.0, false, &free_s);
  const double start_move = moved(1.0, true, &start_s);
  const double zero_move = moved(1.0, false, &zero_s);
  ASSERT_TRUE(free_s.usable && start_s.usable && zero_s.usable);
  EXPECT_GT(free_move, 0.0);
  EXPECT_LT(start_move, 0.7 * free_move);
  EXPECT_LT(start_move, zero_move);
  EXPECT_LT(start_s.final_cost, start_s.initial_cost);
  EXPECT_GT(start_s.initial_cost, 0.0);
}

}  // namespace
}  // namespace odotune::learned
