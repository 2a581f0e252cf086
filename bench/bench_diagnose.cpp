// Speed of the sim-to-real diagnosis (docs/benchmarks.md; the aims: a
// five-minute 100 Hz track well under a minute, cost linear in the track's
// length): diagnose() end to end (sensor checks, model
// selection over the wheel effects, location, findings).
//   BM_Diagnose/300s_100Hz: scenarios/track3.yaml (corridor circuit with
//     radius_error, speed_radius, lateral_skid and gyro_bias) with every
//     sensor at 100 Hz, its motion repeated until it lasts at least 300 s,
//     ground truth as the reference. One diagnosis per iteration (wall time;
//     the counters say how many findings and reference samples).
//   BM_DiagInput: building the diagnosis input from the track alone.
//   BM_DiagnoseScaling/<minutes>/<rate>: the circuit of
//     tests/diagnose/sim_track.h (lane change, corners, a stop, spins) for
//     1, 5, 10, 20 minutes with encoders, commands, gyro and ground truth
//     (sigma 5 mm) all at 10, 50 or 100 Hz, and radius_error, lateral_skid
//     and gyro_bias acting: the table "Diagnosis cost by track length and
//     rate" of docs/benchmarks.md (--benchmark_filter=Scaling). Counters:
//     the timing breakdown of Diagnosis::timing and Selection::timing.
// Breakdown of one recording (or several, pooled as `odotune diagnose FILE...`
// pools them; --from/--to crop each) instead of benchmarks:
//   bench_diagnose --track FILE [--track FILE...] [--from S] [--to S] [--window S]
// prints the diagnosis' first line, its timing (sensors, selection: search,
// discrete searches, final fit; locate and findings) and the time of every
// search record (step, phase, candidate).
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/diagnosis.h>
#include <odotune/diagnose/diagnosis_summary.h>
#include <odotune/diagnose/recordings.h>
#include <odotune/formats/scenario_yaml.h>
#include <odotune/sim/motion_profile.h>
#include <odotune/sim/simulator.h>
#include <odotune/tracks/track_io.h>

#include "tests/diagnose/sim_track.h"

namespace {

using namespace odotune;

tracks::Track five_minutes_at_100hz() {
  sim::Scenario sc = odotune::formats::load_scenario(std::string(ODOTUNE_SOURCE_DIR) +
                                                     "/scenarios/track3.yaml");
  sc.sensors.encoders.rate_hz = 100.0;
  sc.sensors.commands.rate_hz = 100.0;
  sc.sensors.gyro.rate_hz = 100.0;
  sc.sensors.ground_truth.rate_hz = 100.0;
  const std::vector<sim::Segment> lap = sc.motion.segments;
  while (sim::MotionProfile(sc.motion).duration_s() < 300.0)
    sc.motion.segments.insert(sc.motion.segments.end(), lap.begin(), lap.end());
  return sim::simulate(sc);
}

const tracks::Track& track() {
  static const tracks::Track t = five_minutes_at_100hz();
  return t;
}

void timing_counters(benchmark::State& state, const diagnose::Diagnosis& d) {
  state.counters["findings"] = static_cast<double>(d.findings.size());
  state.counters["sensors_s"] = d.timing.sensors_s;
  state.counters["select_s"] = d.timing.select_s;
  state.counters["discrete_s"] = d.selection.timing.discrete_s;
  state.counters["final_s"] = d.selection.timing.final_s;
  state.counters["locate_s"] = d.timing.locate_s;
  state.counters["fits"] = d.selection.timing.fits;
}

void BM_Diagnose(benchmark::State& state) {
  const diagnose::DiagInput in = diagnose::build_diag_input(track());
  diagnose::Diagnosis d;
  for (auto _ : state) {
    d = diagnose::diagnose(in);
    benchmark::DoNotOptimize(d.final_pos_rmse_m);
  }
  timing_counters(state, d);
  state.counters["ref_samples"] = static_cast<double>(in.ref_t_s.size());
  state.counters["track_s"] = in.ref_t_s.back() - in.ref_t_s.front();
}
BENCHMARK(BM_Diagnose)->Name("BM_Diagnose/300s_100Hz")->Unit(benchmark::kSecond)->UseRealTime()->Iterations(3);

void BM_DiagInput(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(diagnose::build_diag_input(track()).ref_t_s.size());
}
BENCHMARK(BM_DiagInput)->Unit(benchmark::kMillisecond);

// The scaling track: `minutes` of the sim_track circuit, every sensor at rate_hz.
diagnose::DiagInput scaling_input(int minutes, int rate_hz) {
  testing_support::SimTrackOptions o;
  o.duration_s = 60.0 * minutes;
  o.odo_rate_hz = rate_hz;
  o.gyro_rate_hz = rate_hz;
  o.gt_rate_hz = rate_hz;
  o.gt_sigma_m = 0.005;
  o.effects = {"radius_error:scale_l=0.997,scale_r=1.003", "lateral_skid:k=0.02", "gyro_bias:b=0.0015"};
  o.seed = 7;
  return diagnose::build_diag_input(testing_support::simulate_track(o));
}

void BM_DiagnoseScaling(benchmark::State& state) {
  const diagnose::DiagInput in = scaling_input(static_cast<int>(state.range(0)),
                                               static_cast<int>(state.range(1)));
  diagnose::Diagnosis d;
  for (auto _ : state) {
    d = diagnose::diagnose(in);
    benchmark::DoNotOptimize(d.final_pos_rmse_m);
  }
  timing_counters(state, d);
  state.counters["track_s"] = in.ref_t_s.back() - in.ref_t_s.front();
}
BENCHMARK(BM_DiagnoseScaling)
    ->ArgsProduct({{1, 5, 10, 20}, {10, 50, 100}})
    ->ArgNames({"min", "Hz"})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

// --track mode: the breakdown of one recording, or of several pooled
// (header comment).
int breakdown(const std::vector<std::string>& paths, double from_s, double to_s, double window_s) {
  std::vector<diagnose::DiagInput> parts;
  for (const std::string& path : paths) {
    parts.push_back(diagnose::build_diag_input(tracks::read_track(path)));
    if (from_s > -1e299 || to_s < 1e299) parts.back() = diagnose::crop(parts.back(), from_s, to_s);
  }
  diagnose::DiagnoseOptions o;
  o.select.fit.window_s = window_s;
  const auto t0 = std::chrono::steady_clock::now();
  const diagnose::PooledDiagnosis pd = diagnose::diagnose_recordings(parts, {}, o);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const diagnose::Diagnosis& d = pd.pooled;
  const diagnose::DiagInput& in = pd.input;
  const auto lines = diagnose::diagnosis_summary(d);
  fmt::print("{}\n", lines.empty() ? "" : lines.front());
  const auto& st = d.selection.timing;
  fmt::print(
      "track {:.1f} s, {} odometry nodes, {} reference samples (every {}th in the selection), {} windows of {:g} s\n"
      "wall {:.2f} s: sensors {:.2f}, select {:.2f} (search {:.2f} incl. discrete {:.2f}, final {:.2f}; "
      "{} fits), locate+findings {:.2f}\n",
      in.ref_t_s.back() - in.ref_t_s.front(), in.odo_t_s.size(), in.ref_t_s.size(), d.selection.ref_stride,
      d.selection.num_windows, d.selection.window_s, wall, d.timing.sensors_s, d.timing.select_s, st.search_s,
      st.discrete_s, st.final_s, st.fits, d.timing.locate_s);
  std::map<std::string, double> by_candidate;
  for (const auto& r : d.selection.records) {
    fmt::print("  {:>2} {:<9} {:<18} {:7.2f} s {}\n", r.step, r.phase, r.candidate, r.time_s,
               r.accepted ? "accepted" : "");
    by_candidate[r.candidate] += r.time_s;
  }
  fmt::print("by candidate:");
  for (const auto& [c, t] : by_candidate) fmt::print(" {} {:.2f};", c.empty() ? "baseline" : c, t);
  fmt::print("\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> track_paths;
  double from_s = -1e300, to_s = 1e300, window_s = 20.0;
  for (int i = 1; i + 1 < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--track") track_paths.push_back(argv[i + 1]);
    if (a == "--from") from_s = std::atof(argv[i + 1]);
    if (a == "--to") to_s = std::atof(argv[i + 1]);
    if (a == "--window") window_s = std::atof(argv[i + 1]);
  }
  if (!track_paths.empty()) {
    try {
      return breakdown(track_paths, from_s, to_s, window_s);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_diagnose: %s\n", e.what());
      return 1;
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
