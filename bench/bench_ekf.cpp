// EKF replay speed (docs/benchmarks.md).
//   BM_EkfStep:   the straightforward fixed-size-Eigen EKF (odotune/filters/ekf.h),
//                 one predict per odometry step — the reference.
//   BM_FastReplay: the segment-batched replay the tuner uses
//                 (odotune/objectives/replay.h), same numbers.
//   BM_PsoTune:   one full PSO tune (50 particles × 150 iterations) on
//                 Track 1, end to end, swarm evaluated on all threads.
// Counters: ns_per_step is wall time per filter step on one core.
#include <benchmark/benchmark.h>

#include <string>

#include <odotune/jobs/tune_job.h>
#include <odotune/objectives/param_space.h>
#include <odotune/objectives/replay.h>
#include <odotune/tracks/track_io.h>

namespace {

using odotune::filters::NoiseModel;

const odotune::jobs::PreparedTrack& track1() {
  static const odotune::tracks::Track track = odotune::tracks::read_track(std::string(ODOTUNE_SOURCE_DIR) +
                                                                          "/data/tracks/track1.csv");
  static const odotune::jobs::PreparedTrack prepared = odotune::jobs::prepare_track(track);
  return prepared;
}

// A mid-box configuration of each model.
odotune::filters::NoiseParams mid_noise(NoiseModel model) {
  const auto space = odotune::objectives::ParamSpace::for_model(model);
  auto [lo, hi] = space.box();
  std::vector<double> x(lo.size());
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = lo[i] + 0.3 * (hi[i] - lo[i]);
  return space.to_noise(space.to_physical(x));
}

void BM_EkfStep(benchmark::State& state) {
  const auto model = static_cast<NoiseModel>(state.range(0));
  const auto& t = track1();
  const auto noise = mid_noise(model);
  for (auto _ : state) benchmark::DoNotOptimize(odotune::objectives::replay_ekf(t.input, noise));
  const double steps = static_cast<double>(t.input.steps.size());
  state.counters["ns_per_step"] = benchmark::Counter(steps * static_cast<double>(state.iterations()),
                                                     benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetLabel(std::string(odotune::filters::to_string(model)));
}

void BM_FastReplay(benchmark::State& state) {
  const auto model = static_cast<NoiseModel>(state.range(0));
  const auto& t = track1();
  const auto noise = mid_noise(model);
  for (auto _ : state) benchmark::DoNotOptimize(t.fast->evaluate(noise));
  const double steps = static_cast<double>(t.fast->steps());
  state.counters["ns_per_step"] = benchmark::Counter(steps * static_cast<double>(state.iterations()),
                                                     benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetLabel(std::string(odotune::filters::to_string(model)));
}

void BM_PsoTune(benchmark::State& state) {
  const auto model = static_cast<NoiseModel>(state.range(0));
  const auto& t = track1();
  odotune::jobs::TuneRequest req;
  req.model = model;
  req.mode = odotune::objectives::FitnessMode::rmse_mae_maxe;
  req.seed = 1;
  long evals = 0;
  for (auto _ : state) {
    auto out = odotune::jobs::run_tune({&t}, req);
    evals = out.summary.evaluations;
    benchmark::DoNotOptimize(out);
  }
  state.counters["evaluations"] = static_cast<double>(evals);
  state.counters["ns_per_step_all_threads"] = benchmark::Counter(
      static_cast<double>(evals) * static_cast<double>(t.fast->steps()) *
          static_cast<double>(state.iterations()),
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetLabel(std::string(odotune::filters::to_string(model)));
}

}  // namespace

BENCHMARK(BM_EkfStep)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FastReplay)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PsoTune)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

BENCHMARK_MAIN();
