// Learned odometry speed (Fariña et al., Sensors 2023, 23,
// 961: the nets "must retrain on the robot in milliseconds").
//   BM_TrainVelocityNet: one training run of a V net (5 units, 186 weights)
//       on N windows of 20 steps, 100 LM iterations at most, BPTT or
//       autodiff Jacobians (arg 1: 0 = BPTT, 1 = Ceres autodiff).
//   BM_RetrainVelocityNet: one online refit (paper §4.2): 300 windows,
//       warm start from a trained net, the refit's settings
//       (default_retrain_training: 10 iterations at the final loss scale).
//   BM_TrainSlipNet: one training run of a detector net (10 units, 651
//       weights) on N windows, 30 iterations at most.
//   BM_PredictVelocityNet / BM_PredictSlipNet: one inference step (one
//       window of 20 steps through the net).
//   BM_LearnedOdometryStep: one step of the learned odometry (both V and W
//       nets, window shift included).
//   BM_UkfStep: one fusion step (predict + odometry + external + gyro).
//   BM_PoseUkfStep: one step of the fusion with fixes (predict through the
//       unicycle + odometry + a position fix), odotune/filters/pose_velocity_ukf.h.
// The windows come from a fixed synthetic drive (a sum of sines, 10 Hz), so
// the figures are the cost of the maths, not of a particular track.
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <vector>

#include <odotune/filters/pose_velocity_ukf.h>
#include <odotune/filters/velocity_ukf.h>
#include <odotune/learned/learned_fusion.h>
#include <odotune/learned/learned_odometry.h>
#include <odotune/learned/lstm.h>
#include <odotune/learned/lstm_training.h>

namespace {

using odotune::learned::LstmTrainingOptions;
using odotune::learned::SequenceSet;

// Windows of (Δct_r, Δct_l, previous V) → V of a drive with V, W sums of sines
// (8800 counts per rev, 0.32 m wheels, D 0.65 m, right tyre 1 % small).
SequenceSet velocity_windows(int n, int inputs = 3) {
  SequenceSet s;
  s.window = 20;
  s.inputs = inputs;
  auto v_at = [](int k) { return 0.6 + 0.4 * std::sin(0.031 * k) + 0.1 * std::sin(0.17 * k); };
  auto w_at = [](int k) { return 0.5 * std::sin(0.023 * k + 1.0); };
  const double ticks_per_m = 8800.0 / (2.0 * std::numbers::pi * 0.32);
  std::vector<double> rows(static_cast<std::size_t>(20 * inputs));
  for (int w = 0; w < n; ++w) {
    for (int t = 0; t < 20; ++t) {
      const int k = w + t;
      const double v = v_at(k), om = w_at(k);
      double* r = &rows[static_cast<std::size_t>(t * inputs)];
      for (int i = 0; i < inputs; ++i) r[i] = 0.0;
      r[0] = (v + 0.325 * om) * 0.1 * ticks_per_m / 0.99;
      r[1] = (v - 0.325 * om) * 0.1 * ticks_per_m;
      r[inputs - 1] = v_at(k - 1);
      if (inputs == 5) r[2] = 20.0 + 10.0 * v, r[3] = 20.0 + 9.0 * v;
    }
    s.add(rows.data(), v_at(w + 19));
  }
  return s;
}

void BM_TrainVelocityNet(benchmark::State& state) {
  const SequenceSet train = velocity_windows(static_cast<int>(state.range(0)));
  LstmTrainingOptions o;
  o.jacobian = state.range(1) == 0 ? LstmTrainingOptions::Jacobian::bptt
                                   : LstmTrainingOptions::Jacobian::autodiff;
  int iterations = 0;
  for (auto _ : state) {
    odotune::learned::VelocityNet net;
    const auto s = odotune::learned::train_lstm(net, train, SequenceSet{}, o);
    iterations = s.iterations;
    benchmark::DoNotOptimize(net.weights.data());
  }
  state.counters["lm_iterations"] = iterations;
}
BENCHMARK(BM_TrainVelocityNet)->Args({800, 0})->Args({800, 1})->Unit(benchmark::kMillisecond);

void BM_RetrainVelocityNet(benchmark::State& state) {
  const SequenceSet train = velocity_windows(800);
  odotune::learned::VelocityNet trained;
  odotune::learned::train_lstm(trained, train, SequenceSet{}, LstmTrainingOptions{});
  SequenceSet fresh = velocity_windows(300);
  for (double& y : fresh.y) y *= 0.97;                                   // a tyre change
  LstmTrainingOptions o = odotune::learned::default_retrain_training();  // what the online refit runs
  o.jacobian = state.range(0) == 0 ? LstmTrainingOptions::Jacobian::bptt
                                   : LstmTrainingOptions::Jacobian::autodiff;
  for (auto _ : state) {
    odotune::learned::VelocityNet net = trained;
    odotune::learned::retrain_lstm(net, fresh, o);
    benchmark::DoNotOptimize(net.weights.data());
  }
}
BENCHMARK(BM_RetrainVelocityNet)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_TrainSlipNet(benchmark::State& state) {
  const SequenceSet train = velocity_windows(static_cast<int>(state.range(0)), 5);
  LstmTrainingOptions o;
  o.max_iterations = 30;
  for (auto _ : state) {
    odotune::learned::SlipNet net;
    net.activation = odotune::learned::OutputActivation::relu;
    odotune::learned::train_lstm(net, train, SequenceSet{}, o);
    benchmark::DoNotOptimize(net.weights.data());
  }
}
BENCHMARK(BM_TrainSlipNet)->Arg(800)->Unit(benchmark::kMillisecond);

template <typename Net>
void predict_bench(benchmark::State& state, int inputs) {
  const SequenceSet s = velocity_windows(64, inputs);
  Net net;
  for (std::size_t i = 0; i < net.weights.size(); ++i)
    net.weights[i] = 0.05 * std::sin(1.3 * static_cast<double>(i));
  std::size_t w = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(net.predict(s.window_data(w)));
    w = (w + 1) % s.size();
  }
}
void BM_PredictVelocityNet(benchmark::State& state) { predict_bench<odotune::learned::VelocityNet>(state, 3); }
void BM_PredictSlipNet(benchmark::State& state) { predict_bench<odotune::learned::SlipNet>(state, 5); }
BENCHMARK(BM_PredictVelocityNet)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PredictSlipNet)->Unit(benchmark::kMicrosecond);

void BM_LearnedOdometryStep(benchmark::State& state) {
  odotune::learned::LearnedOdometryModel model;
  model.ticks_per_rev = 8800;
  odotune::learned::VelocityNet v_net, w_net;
  for (std::size_t i = 0; i < v_net.weights.size(); ++i) {
    v_net.weights[i] = 0.05 * std::sin(1.3 * static_cast<double>(i));
    w_net.weights[i] = 0.05 * std::cos(1.7 * static_cast<double>(i));
  }
  model.v_net = v_net;
  model.w_net = w_net;
  // One step of a track, its increments varied from call to call.
  odotune::learned::FusionInput in;
  in.dticks_l = {40.0};
  in.dticks_r = {41.0};
  in.v_kin = {0.5};
  in.w_kin = {0.1};
  in.gyro_z = {0.0};
  odotune::learned::LearnedOdometryStepper stepper(&model);
  double k = 0, v = 0, w = 0;
  for (auto _ : state) {
    in.dticks_l[0] = 40.0 + std::sin(k);
    in.dticks_r[0] = 41.0 + std::cos(k);
    const auto vw = stepper.step(in, 0, v, w);
    v = vw[0];
    w = vw[1];
    k += 0.1;
    benchmark::DoNotOptimize(v);
  }
}
BENCHMARK(BM_LearnedOdometryStep)->Unit(benchmark::kMicrosecond);

void BM_UkfStep(benchmark::State& state) {
  odotune::filters::VelocityUkf ukf(odotune::filters::UkfParams{});
  const odotune::filters::VelocityCov R_odo = odotune::filters::VelocityCov::Identity() * 1e-3;
  const odotune::filters::VelocityCov R_ext = odotune::filters::VelocityCov::Identity() * 4e-4;
  double k = 0;
  for (auto _ : state) {
    ukf.predict(0.1);
    ukf.update({0.5 + 0.1 * std::sin(k), 0.2}, R_odo);
    ukf.update({0.5, 0.2 + 0.01 * std::cos(k)}, R_ext);
    ukf.update_yaw_rate(0.2, 4e-6);
    k += 0.1;
    benchmark::DoNotOptimize(ukf.state().data());
  }
}
BENCHMARK(BM_UkfStep)->Unit(benchmark::kMicrosecond);

void BM_PoseUkfStep(benchmark::State& state) {
  odotune::filters::PoseVelocityUkf ukf(odotune::filters::PoseUkfParams{});
  const Eigen::Matrix2d R_odo = Eigen::Matrix2d::Identity() * 1e-3;
  const Eigen::Matrix2d R_fix = Eigen::Matrix2d::Identity() * 0.01;
  double k = 0;
  for (auto _ : state) {
    ukf.predict(0.1);
    ukf.update_velocity(0.5 + 0.1 * std::sin(k), 0.2, R_odo);
    ukf.update_position(0.05 * k, 0.0, R_fix);
    k += 0.1;
    benchmark::DoNotOptimize(ukf.state().data());
  }
}
BENCHMARK(BM_PoseUkfStep)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
