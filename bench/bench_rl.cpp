// robot_localization's EKF replayed from the Husky bag (docs/benchmarks.md,
// "robot_localization's EKF replayed", for the figures, the machine and
// robot_localization's own filter core timed side by side).
//   BM_RlReplayHusky: one replay of test1 (395 s) with the user's file
//       husky_ekf.yaml: wheel odometry (10 Hz), IMU (30 Hz: orientation,
//       rates, accelerations) and GPS (2.5 Hz) through navsat — the unit of
//       work of a tune.
//   BM_RlReplayHuskyBatch: 8 noise settings of the same file replayed
//       together by replay_batch (filters::rl::kLanes filters in lock step);
//       ms_per_replay is the time per setting. The aim: a replay at least 20×
//       cheaper than robot_localization's own filter core.
//   BM_RlReplayBag1: the same bag with robot_localization's bag1 test file
//       (odometry and IMU).
//   BM_RlSchedule: laying out the node's timer and queue once.
// Counters: measurements per replay; ns_per_measurement (shown with an "s")
// and ms_per_replay (likewise) of wall time on one core.
// Measured 2026-11-28 (2 vCPUs of a Sapphire Rapids Xeon, AVX-512): one replay
// 27.0 ms, 10.4 ms per replay in a batch (43.9 ms before); robot_localization's
// core 284 ms side by side (10.5× and 27×; interleaved at random, 36–38× for
// the batch).
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <vector>

#include <odotune/rlnode/gps_alignment.h>
#include <odotune/rlnode/params.h>
#include <odotune/rlnode/recording.h>
#include <odotune/rlnode/replay.h>

namespace {

using namespace odotune::rlnode;

const std::filesystem::path kBags = std::filesystem::path(ODOTUNE_SOURCE_DIR) /
                                    "../shared/data/real/robot_localization_bags";

RecordingOptions mounting() {
  RecordingOptions o;
  Pose3 mount;
  mount.t = {0.0, -0.3, 0.52};
  mount.R = rotation_rpy(std::numbers::pi / 2, 0.0, -std::numbers::pi / 2);
  o.frames["imu_link"] = mount;
  return o;
}

const Recording& husky() {
  static const Recording rec = [] {
    Recording r = load_recording(kBags / "test1.bag", read_rl_params(kBags / "husky_ekf.yaml"), mounting());
    r.gps_transform = fit_gps_alignment(r, settings_of(r.params), 60.0).transform;
    return r;
  }();
  return rec;
}

const Recording& bag1() {
  static const Recording rec = [] {
    const auto path = std::filesystem::temp_directory_path() / "odotune-bench-bag1.yaml";
    std::ofstream(path)
        << "ekf:\n  ros__parameters:\n    frequency: 30.0\n    sensor_timeout: 0.1\n"
           "    odom0: /husky_velocity_controller/odom\n    imu0: /imu/data\n"
           "    odom0_config: [false, false, false, false, false, false, true, true, true, false, "
           "false, false, false, false, false]\n"
           "    imu0_config: [false, false, false, true, true, true, false, false, false, true, "
           "true, false, true, true, true]\n"
           "    imu0_remove_gravitational_acceleration: true\n";
    return load_recording(kBags / "test1.bag", read_rl_params(path), mounting());
  }();
  return rec;
}

void run_replays(benchmark::State& state, const Recording& rec) {
  const Schedule schedule = make_schedule(rec);
  const ReplaySettings settings = settings_of(rec.params);
  long processed = 0;
  for (auto _ : state) {
    const ReplayOutput out = replay(rec, schedule, settings);
    processed = out.processed;
    benchmark::DoNotOptimize(out.final_state.data());
  }
  state.counters["measurements"] = static_cast<double>(processed);
  state.counters["ns_per_measurement"] = benchmark::Counter(static_cast<double>(processed) * 1e-9,
                                                            benchmark::Counter::kIsIterationInvariantRate |
                                                                benchmark::Counter::kInvert);
}

void BM_RlReplayHusky(benchmark::State& state) { run_replays(state, husky()); }

// kLanes settings around the file's (process noise and the inputs'
// covariances scaled, as a tune's candidates are), replayed together.
void BM_RlReplayHuskyBatch(benchmark::State& state) {
  const Recording& rec = husky();
  const Schedule schedule = make_schedule(rec);
  std::vector<ReplaySettings> settings(odotune::filters::rl::kLanes, settings_of(rec.params));
  for (std::size_t k = 0; k < settings.size(); ++k) {
    settings[k].process_noise *= std::pow(10.0, 0.25 * static_cast<double>(k) - 1.0);
    for (double& c : settings[k].covariance_scale) c = std::pow(2.0, static_cast<double>(k % 3) - 1.0);
  }
  long processed = 0;
  for (auto _ : state) {
    const std::vector<ReplayOutput> out = replay_batch(rec, schedule, settings);
    processed = out.front().processed;
    benchmark::DoNotOptimize(out.back().final_state.data());
  }
  const auto replays = static_cast<double>(settings.size());
  state.counters["replays"] = replays;
  state.counters["ms_per_replay"] = benchmark::Counter(
      replays * 1e-3, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["measurements"] = static_cast<double>(processed);
}
void BM_RlReplayBag1(benchmark::State& state) { run_replays(state, bag1()); }

void BM_RlSchedule(benchmark::State& state) {
  const Recording& rec = husky();
  for (auto _ : state) benchmark::DoNotOptimize(make_schedule(rec).events.size());
}

}  // namespace

BENCHMARK(BM_RlReplayHusky)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_RlReplayHuskyBatch)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_RlReplayBag1)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_RlSchedule)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
