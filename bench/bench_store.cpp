// Results store write cost (docs/benchmarks.md): what one finished run costs
// the grid to make durable, i.e. Store::add — its own transaction in WAL mode
// with synchronous=FULL (an fsync per commit) — for a run like the study's
// (5 parameters, a convergence log of 151 points).
//   BM_StoreAdd: one add, to a store growing over the benchmark.
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <filesystem>
#include <string>

#include <odotune/results/store.h>

namespace {

namespace fs = std::filesystem;
using odotune::results::RunRecord;

RunRecord study_like_run(std::uint64_t seed) {
  RunRecord r;
  r.model = "gyro";
  r.track = "track3";
  r.mode = 7;
  r.seed = seed;
  r.param_names = {"a1", "a2", "b1_s_rad", "b2_s_rad", "q_mm2"};
  r.params = {0.012, 0.034, 0.001, 0.002, 3600.0};
  r.best_fitness = 0.123;
  r.baseline = {0.16, 0.15, 0.28};
  r.tuned = {0.048, 0.041, 0.128};
  r.evaluations = 7550;
  r.seconds = 0.2;
  r.termination = "budget";
  for (long i = 0; i <= 150; ++i) r.convergence.push_back({50 * (i + 1), 0.5 / static_cast<double>(i + 1)});
  return r;
}

void BM_StoreAdd(benchmark::State& state) {
  const fs::path dir = fs::temp_directory_path() / ("odotune-bench-store-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    const std::string text = "format: odotune-experiment/1\nname: bench\n";
    odotune::results::Store store(dir / "s.sqlite",
                                  {"bench", text, odotune::results::experiment_hash(text), "bench", ""});
    std::uint64_t seed = 0;
    for (auto _ : state) store.add(study_like_run(++seed));
    state.counters["runs"] = static_cast<double>(seed);
  }
  fs::remove_all(dir);
}
BENCHMARK(BM_StoreAdd)->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
