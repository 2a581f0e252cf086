// Online odometry calibration speed (Fariña, Toledo & Acosta,
// RA-L 2026, Table I: 0.5–1.9 ms per PF iteration, Table II: 0.89 ms for the
// adaptive PF at ≈ 8000 particles, 0.46 ms for the DKF).
//   BM_PfStep:  one PfCalibrator::step() (prediction, update, estimate,
//               resampling every iteration) at N = 1000, 5000, 8000
//               particles, for each resampler, with 1 and 2 threads.
//   BM_Resample: the resampler alone (N → N draws).
//   BM_DkfStep: one DualKf::step().
// Time is per step() (per resampling for BM_Resample, per whole 60 s run
// for BM_AdaptivePfStep); the counter per_particle (per_step) is that time
// divided by the particle count (the run's steps), printed in seconds with an
// SI prefix (e.g. 25.1n = 25.1 ns).
// A fixed synthetic sample stream (10 Hz, a varied drive) is cycled; the
// filter state carries on across the benchmark's iterations.
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <odotune/filters/dual_kf.h>
#include <odotune/filters/pf_calibrator.h>
#include <odotune/filters/resampling.h>

namespace {

using odotune::filters::CalibSample;
using odotune::filters::Resampler;

// 60 s of samples at 10 Hz from R_R = 0.318, R_L = 0.326, D = 0.65, with a
// deterministic ±0.02 "noise" pattern on the measurement.
const std::vector<CalibSample>& stream() {
  static const std::vector<CalibSample> samples = [] {
    std::vector<CalibSample> out;
    const double rr = 0.318, rl = 0.326, d = 0.65;
    for (int k = 0; k < 600; ++k) {
      const double t = 0.1 * k;
      const double v = 0.5 + 0.4 * std::sin(2.0 * std::numbers::pi * t / 23.0);
      const double w = 0.9 * std::sin(2.0 * std::numbers::pi * t / 13.0);
      CalibSample s;
      s.dt_s = k == 0 ? 0.0 : 0.1;
      s.omega_r_rad_s = (v + 0.5 * w * d) / rr;
      s.omega_l_rad_s = (v - 0.5 * w * d) / rl;
      s.v_m_s = v + 0.02 * std::sin(12.9898 * k);
      s.w_rad_s = w + 0.02 * std::cos(78.233 * k);
      out.push_back(s);
    }
    return out;
  }();
  return samples;
}

void set_counters(benchmark::State& state, double particles) {
  state.counters["per_particle"] = benchmark::Counter(static_cast<double>(state.iterations()) * particles,
                                                      benchmark::Counter::kIsRate |
                                                          benchmark::Counter::kInvert);
}

// Args: particles, resampler, threads.
void BM_PfStep(benchmark::State& state) {
  odotune::filters::PfCalibratorParams p;
  p.particles = static_cast<int>(state.range(0));
  p.resampler = static_cast<Resampler>(state.range(1));
  p.threads = static_cast<int>(state.range(2));
  p.policy = odotune::filters::ResamplePolicy::every_step;
  odotune::filters::PfCalibrator pf(p);
  const auto& samples = stream();
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(pf.step(samples[k]));
    k = (k + 1) % samples.size();
  }
  set_counters(state, static_cast<double>(p.particles));
  state.SetLabel(std::string(odotune::filters::to_string(p.resampler)) +
                 " threads=" + std::to_string(p.threads));
}

// The adaptive PF from 8000 particles with the paper's defaults (policy neff):
// what a run costs on average, N adapting as it converges.
void BM_AdaptivePfStep(benchmark::State& state) {
  odotune::filters::PfCalibratorParams p = odotune::filters::PfCalibratorParams::adaptive_defaults();
  p.threads = static_cast<int>(state.range(0));
  const auto& samples = stream();
  double particle_steps = 0.0;
  long steps = 0;
  for (auto _ : state) {
    state.PauseTiming();
    odotune::filters::PfCalibrator pf(p);
    state.ResumeTiming();
    for (const CalibSample& s : samples) particle_steps += pf.step(s).particles;
    steps += static_cast<long>(samples.size());
  }
  state.counters["per_step"] = benchmark::Counter(static_cast<double>(steps),
                                                  benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["mean_particles"] = particle_steps / static_cast<double>(steps);
  state.SetLabel("threads=" + std::to_string(p.threads));
}

// Args: particles, resampler.
void BM_Resample(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const auto scheme = static_cast<Resampler>(state.range(1));
  std::vector<double> w(n);
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    sum += (w[i] = std::exp(-0.5 * std::pow(std::sin(0.37 * static_cast<double>(i)) * 3.0, 2)));
  for (double& x : w) x /= sum;
  std::vector<int> out(n);
  std::uint64_t it = 0;
  for (auto _ : state) {
    odotune::filters::resample(scheme, w, 1, ++it, out);
    benchmark::DoNotOptimize(out.data());
  }
  set_counters(state, static_cast<double>(n));
  state.SetLabel(std::string(odotune::filters::to_string(scheme)));
}

void BM_DkfStep(benchmark::State& state) {
  odotune::filters::DualKf dkf(odotune::filters::DualKfParams{});
  const auto& samples = stream();
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(dkf.step(samples[k]));
    k = (k + 1) % samples.size();
  }
}

}  // namespace

BENCHMARK(BM_PfStep)
    ->ArgsProduct({{1000, 5000, 8000}, {0, 1, 2, 3}, {1, 2}})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();
BENCHMARK(BM_AdaptivePfStep)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Resample)->ArgsProduct({{1000, 8000}, {0, 1, 2, 3}})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DkfStep)->Unit(benchmark::kNanosecond);

BENCHMARK_MAIN();
