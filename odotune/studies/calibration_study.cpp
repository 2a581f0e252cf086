#include <odotune/studies/calibration_study.h>

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include <odotune/core/counter_rng.h>
#include <odotune/core/non_finite.h>
#include <odotune/core/stopwatch.h>
#include <odotune/core/why.h>
#include <odotune/filters/pf_calibrator.h>
#include <odotune/sim/simulator.h>

namespace odotune::studies {

namespace {

using core::seconds_since;

using core::kNaN;

// Counter-RNG streams of the per-run draws (odotune/core/counter_rng.h); any fixed,
// distinct values do.
constexpr std::uint64_t kTruthStream = 0x7472757468ULL;  // "truth"
constexpr std::uint64_t kDkfStream = 0x646b66ULL;        // "dkf"

double uniform_in(double lo, double hi, std::uint64_t seed, std::uint64_t dim, std::uint64_t stream) {
  return lo + (hi - lo) * core::counter_uniform01(seed, 0, 0, dim, stream);
}

int threads_for(const StudyOptions& o) { return o.threads > 0 ? o.threads : omp_get_max_threads(); }

// A simulated run prepared for calibration.
struct PreparedRun {
  calibration::CalibrationInput constant, step;
};

calibration::CalibrationInput simulate_input(const sim::Scenario& scenario, const McDraw& draw) {
  const tracks::Track track = sim::simulate(run_scenario(scenario, draw));
  calibration::CalibrationInput in = calibration::build_calibration_input(
      track, calibration::CalibrationInputOptions{});
  if (!in.truth)
    throw std::invalid_argument("scenario '" + scenario.name + "': the simulated track has no truth");
  if (in.samples.empty() || in.t.empty())
    throw std::invalid_argument("scenario '" + scenario.name + "': no calibration samples");
  return in;
}

// Runs `task(k)` for k in [0, count) on `threads` threads (dynamic
// schedule), reporting progress; rethrows the first exception (as
// std::invalid_argument / std::runtime_error with its message) after the loop.
template <class Task>
void parallel_tasks(long count, int threads, long* done, long total, const StudyProgress& progress,
                    const Task& task) {
  std::string failure;
  bool invalid = false;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (long k = 0; k < count; ++k) {
    bool skip = false;
#pragma omp critical(odotune_study)
    skip = !failure.empty();
    if (skip) continue;
    try {
      task(k);
    } catch (const std::invalid_argument& ex) {
#pragma omp critical(odotune_study)
      if (failure.empty()) {
        failure = ex.what();
        invalid = true;
      }
    } catch (const std::exception& ex) {
#pragma omp critical(odotune_study)
      if (failure.empty()) failure = ex.what();
    }
#pragma omp critical(odotune_study)
    {
      ++*done;
      if (progress) progress(*done, total);
    }
  }
  if (!failure.empty()) {
    if (invalid) throw std::invalid_argument(failure);
    throw std::runtime_error(failure);
  }
}

ParamTrace param_trace(const calibration::CalibrationResult& r, const calibration::CalibrationInput& in) {
  ParamTrace p;
  const std::size_t n = r.trace.t.size();
  p.t_s = r.trace.t;
  for (auto* v :
       {&p.r_right_m, &p.r_left_m, &p.wheel_base_m, &p.true_r_right_m, &p.true_r_left_m, &p.true_wheel_base_m})
    v->reserve(n);
  p.particles.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const filters::CalibEstimate& e = r.trace.estimate[i];
    p.r_right_m.push_back(e.params.wheel_radius_right_m);
    p.r_left_m.push_back(e.params.wheel_radius_left_m);
    p.wheel_base_m.push_back(e.params.wheel_base_m);
    p.particles.push_back(e.particles);
    const filters::OdometryParams& t = in.truth->at(p.t_s[i]);
    p.true_r_right_m.push_back(t.wheel_radius_right_m);
    p.true_r_left_m.push_back(t.wheel_radius_left_m);
    p.true_wheel_base_m.push_back(t.wheel_base_m);
  }
  return p;
}

// |final − truth at the end| of the track's score.
struct FinalErrors {
  double rr = kNaN, rl = kNaN, d = kNaN;
};
FinalErrors final_errors(const calibration::TrackCalibrationScore& s) {
  if (!s.truth_final) return {};
  return {std::abs(s.final_params.wheel_radius_right_m - s.truth_final->wheel_radius_right_m),
          std::abs(s.final_params.wheel_radius_left_m - s.truth_final->wheel_radius_left_m),
          std::abs(s.final_params.wheel_base_m - s.truth_final->wheel_base_m)};
}

template <class Run, class Field>
MeanSd stat(const std::vector<Run>& runs, Field field) {
  std::vector<double> v;
  v.reserve(runs.size());
  for (const Run& r : runs) v.push_back(r.*field);
  return mean_sd(v);
}

std::vector<PreparedRun> prepare_runs(const sim::Scenario& constant, const sim::Scenario* step,
                                      const std::vector<McDraw>& draws, int threads, long* done, long total,
                                      const StudyProgress& progress) {
  std::vector<PreparedRun> runs(draws.size());
  parallel_tasks(static_cast<long>(draws.size()), threads, done, total, progress, [&](long r) {
    runs[r].constant = simulate_input(constant, draws[r]);
    if (step) runs[r].step = simulate_input(*step, draws[r]);
  });
  return runs;
}

}  // namespace

MeanSd mean_sd(const std::vector<double>& values) {
  MeanSd out;
  double sum = 0.0;
  for (double v : values)
    if (std::isfinite(v)) sum += v, ++out.n;
  if (out.n == 0) return out;
  out.mean = sum / out.n;
  double ss = 0.0;
  for (double v : values)
    if (std::isfinite(v)) ss += (v - out.mean) * (v - out.mean);
  out.sd = out.n > 1 ? std::sqrt(ss / (out.n - 1)) : 0.0;
  return out;
}

bool StudyOptions::IsValid(std::string* why) const {
  if (runs < 1 || runs > 1000) return core::invalid(why, fmt::format("runs = {} must be in 1..1000", runs));
  if (threads < 0) return core::invalid(why, fmt::format("threads = {} must be >= 0 (0 = all cores)", threads));
  if (!(truth_radius_spread > 0.0 && truth_radius_spread <= 0.1))
    return core::invalid(why, fmt::format("truth_radius_spread = {} must be in (0, 0.1]", truth_radius_spread));
  if (pf_particles < 10 || pf_particles > 1000000)
    return core::invalid(why, fmt::format("pf_particles = {} must be in 10..1000000", pf_particles));
  if (adaptive_initial_particles != 0 &&
      (adaptive_initial_particles < 10 || adaptive_initial_particles > 1000000))
    return core::invalid(why,
                         fmt::format("adaptive_initial_particles = {} must be 0 (default) or in 10..1000000",
                                     adaptive_initial_particles));
  return true;
}

McDraw mc_draw(const StudyOptions& options, const sim::Scenario& scenario, int run) {
  McDraw d;
  d.run = run;
  d.seed = options.seed + static_cast<std::uint64_t>(run);
  const double s = options.truth_radius_spread;
  d.truth_scale_l = uniform_in(1.0 - s, 1.0 + s, d.seed, 0, kTruthStream);
  d.truth_scale_r = uniform_in(1.0 - s, 1.0 + s, d.seed, 1, kTruthStream);
  const filters::PfCalibratorParams ranges;
  d.dkf_initial.wheel_radius_right_m = uniform_in(ranges.wheel_radius_right_m.lo,
                                                  ranges.wheel_radius_right_m.hi, d.seed, 0, kDkfStream);
  d.dkf_initial.wheel_radius_left_m = uniform_in(ranges.wheel_radius_left_m.lo, ranges.wheel_radius_left_m.hi,
                                                 d.seed, 1, kDkfStream);
  d.dkf_initial.wheel_base_m = scenario.robot.wheel_base_m;
  return d;
}

sim::Scenario run_scenario(const sim::Scenario& scenario, const McDraw& draw) {
  sim::Scenario s = scenario;
  s.seed = draw.seed;
  s.effects.radius_error = sim::Effects::RadiusError{draw.truth_scale_l, draw.truth_scale_r};
  return s;
}

void check_study_scenario(const sim::Scenario& scenario, const StudyOptions& options) {
  const std::string name = "scenario '" + scenario.name + "'";
  std::string why;
  if (!sim::validate_scenario(scenario, &why)) throw std::invalid_argument(name + ": " + why);
  const auto& sensors = scenario.sensors;
  if (!sensors.encoders.enabled) throw std::invalid_argument(name + ": needs encoders (sensors.encoders)");
  if (!sensors.ext_velocity.enabled)
    throw std::invalid_argument(name + ": needs the external velocity sensor (sensors.ext_velocity)");
  if (!sensors.ground_truth.enabled)
    throw std::invalid_argument(name + ": needs ground truth (sensors.ground_truth)");
  const filters::PfCalibratorParams pf;
  const double s = options.truth_radius_spread;
  const auto& step = scenario.effects.radius_step;
  const auto check_radius = [&](const char* wheel, double nominal, double step_scale,
                                const filters::PfCalibratorParams::Range& range) {
    for (double scale : {1.0 - s, 1.0 + s, (1.0 - s) * step_scale, (1.0 + s) * step_scale}) {
      const double r = nominal * scale;
      if (r < range.lo || r > range.hi)
        throw std::invalid_argument(
            fmt::format("{}: a true {} radius of {:.5f} m (nominal {} × {:.4f}) would lie outside the PF's "
                        "initial range [{}, {}] m; use a smaller spread or a wheelchair-sized robot",
                        name, wheel, r, nominal, scale, range.lo, range.hi));
    }
  };
  check_radius("right", scenario.robot.wheel_radius_right_m, step ? step->scale_r : 1.0,
               pf.wheel_radius_right_m);
  check_radius("left", scenario.robot.wheel_radius_left_m, step ? step->scale_l : 1.0, pf.wheel_radius_left_m);
  const double base = scenario.robot.wheel_base_m *
                      (scenario.effects.wheel_base_error ? scenario.effects.wheel_base_error->scale : 1.0);
  if (base < pf.wheel_base_m.lo || base > pf.wheel_base_m.hi)
    throw std::invalid_argument(fmt::format("{}: the true wheel base {:.4f} m lies outside the PF's "
                                            "initial range [{}, {}] m",
                                            name, base, pf.wheel_base_m.lo, pf.wheel_base_m.hi));
}

std::vector<PieceConvergence> radius_convergence(
    const ParamTrace& trace, const calibration::TruthSchedule& truth, double start_s, double tolerance) {
  std::vector<PieceConvergence> out(truth.from_s.size());
  for (std::size_t k = 0; k < truth.from_s.size(); ++k) {
    const double from = truth.from_s[k];
    const double to = k + 1 < truth.from_s.size() ? truth.from_s[k + 1] : INFINITY;
    const double origin = k == 0 ? start_s : from;
    const filters::OdometryParams& t = truth.params[k];
    std::vector<double> times;
    std::vector<filters::OdometryParams> est;
    for (std::size_t i = 0; i < trace.t_s.size(); ++i) {
      if (trace.t_s[i] < from || trace.t_s[i] >= to) continue;
      times.push_back(trace.t_s[i]);
      // D pinned to the truth: only the radii decide.
      est.push_back({trace.r_left_m[i], trace.r_right_m[i], t.wheel_base_m});
      const bool within =
          std::abs(trace.r_left_m[i] - t.wheel_radius_left_m) <= tolerance * t.wheel_radius_left_m &&
          std::abs(trace.r_right_m[i] - t.wheel_radius_right_m) <= tolerance * t.wheel_radius_right_m;
      if (within && std::isnan(out[k].reached_s)) out[k].reached_s = trace.t_s[i] - origin;
    }
    const std::optional<double> c = calibration::convergence_time(times, est, t, tolerance);
    if (c) out[k].settled_s = *c - origin;
  }
  return out;
}

// ---------------------------------------------------------------- Table I

std::vector<filters::Resampler> table1_resamplers() {
  using R = filters::Resampler;
  return {R::stratified, R::multinomial, R::residual, R::systematic};
}

std::vector<filters::ResamplePolicy> table1_policies() {
  using P = filters::ResamplePolicy;
  return {P::neff, P::max_weight, P::every_step};
}

ResamplingStudy run_resampling_study(const sim::Scenario& scenario, const StudyOptions& options,
                                     const StudyProgress& progress) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("study: " + why);
  check_study_scenario(scenario, options);
  const auto t0 = std::chrono::steady_clock::now();

  ResamplingStudy out;
  out.scenario = scenario.name;
  out.options = options;
  out.threads_used = threads_for(options);
  for (int r = 0; r < options.runs; ++r) out.draws.push_back(mc_draw(options, scenario, r));
  for (auto rs : table1_resamplers())
    for (auto p : table1_policies()) {
      ResamplingCell c;
      c.resampler = rs;
      c.policy = p;
      c.runs.resize(static_cast<std::size_t>(options.runs));
      out.cells.push_back(std::move(c));
    }

  const long cells = static_cast<long>(out.cells.size());
  const long tasks = cells * options.runs;
  const long total = options.runs + tasks;
  long done = 0;
  if (progress) progress(0, total);
  const std::vector<PreparedRun> runs = prepare_runs(scenario, nullptr, out.draws, out.threads_used, &done,
                                                     total, progress);
  double iterations = 0.0;
  for (const auto& r : runs) iterations += static_cast<double>(r.constant.samples.size());
  out.iterations_per_run = iterations / options.runs;
  out.track_duration_s = runs.front().constant.t.back() - runs.front().constant.t.front();

  // Task k: run k / cells, cell k % cells (all cells of a run close together).
  parallel_tasks(tasks, out.threads_used, &done, total, progress, [&](long k) {
    const auto run = static_cast<std::size_t>(k / cells);
    ResamplingCell& cell = out.cells[static_cast<std::size_t>(k % cells)];
    calibration::CalibrationOptions o;
    o.method = calibration::CalibrationMethod::pf;
    o.pf.particles = options.pf_particles;
    o.pf.resampler = cell.resampler;
    o.pf.policy = cell.policy;
    o.pf.seed = out.draws[run].seed;
    o.pf.threads = 1;  // the study parallelises over tasks
    const calibration::CalibrationInput& in = runs[run].constant;
    const calibration::CalibrationResult res = calibration::run_calibration({&in}, o);
    const calibration::TrackCalibrationScore& s = res.tracks.at(0);
    const FinalErrors e = final_errors(s);
    ResamplingRunResult& rr = cell.runs[run];
    rr.err_rr_m = e.rr;
    rr.err_rl_m = e.rl;
    rr.v_rmse_m_s = s.v_rmse_m_s;
    rr.w_rmse_rad_s = s.w_rmse_rad_s;
    const auto resampled = std::count_if(res.trace.estimate.begin(), res.trace.estimate.end(),
                                         [](const filters::CalibEstimate& x) { return x.resampled; });
    rr.resampled_fraction = res.trace.estimate.empty() ? kNaN
                                                       : static_cast<double>(resampled) /
                                                             static_cast<double>(res.trace.estimate.size());
    rr.ms_per_iteration = res.ms_per_iteration;
  });

  for (ResamplingCell& c : out.cells) {
    using R = ResamplingRunResult;
    c.err_rr_m = stat(c.runs, &R::err_rr_m);
    c.err_rl_m = stat(c.runs, &R::err_rl_m);
    c.v_rmse_m_s = stat(c.runs, &R::v_rmse_m_s);
    c.w_rmse_rad_s = stat(c.runs, &R::w_rmse_rad_s);
    c.resampled_fraction = stat(c.runs, &R::resampled_fraction);
    c.ms_per_iteration = stat(c.runs, &R::ms_per_iteration);
  }
  out.wall_s = seconds_since(t0);
  return out;
}

// ---------------------------------------------------------------- Table II

std::string_view to_string(StudyTrack t) { return t == StudyTrack::step ? "step" : "constant"; }

std::vector<calibration::CalibrationMethod> table2_methods() {
  using M = calibration::CalibrationMethod;
  return {M::adaptive_pf, M::dkf, M::batch_velocity, M::none};
}

namespace {

// The study's Monte Carlo draws, one row per (track, method) of Table II with
// a slot per run, and a slot per run for each online method's traces.
void set_up_rows(CalibrationStudy& out, const sim::Scenario& constant, const StudyOptions& options) {
  for (int r = 0; r < options.runs; ++r) out.draws.push_back(mc_draw(options, constant, r));
  const auto methods = table2_methods();
  for (StudyTrack track : kAllStudyTracks)
    for (calibration::CalibrationMethod m : methods) {
      MethodRow row;
      row.track = track;
      row.method = m;
      row.online = m == calibration::CalibrationMethod::adaptive_pf || m == calibration::CalibrationMethod::dkf;
      row.runs.resize(static_cast<std::size_t>(options.runs));
      out.rows.push_back(std::move(row));
    }
  for (auto* traces : {&out.pf_constant, &out.pf_step, &out.dkf_constant, &out.dkf_step})
    traces->resize(static_cast<std::size_t>(options.runs));
}

// Task k: row k % rows of run k / rows (the row's method on the run's
// track): its final errors and costs, and for an online method its
// convergence times and parameter trace.
void run_table2_task(CalibrationStudy& out, const std::vector<PreparedRun>& runs, const StudyOptions& options,
                     long row_count, long k) {
  const auto run = static_cast<std::size_t>(k / row_count);
  MethodRow& row = out.rows[static_cast<std::size_t>(k % row_count)];
  const bool is_step = row.track == StudyTrack::step;
  const calibration::CalibrationInput& in = is_step ? runs[run].step : runs[run].constant;
  calibration::CalibrationOptions o;
  o.method = row.method;
  o.pf = filters::PfCalibratorParams::adaptive_defaults();
  if (options.adaptive_initial_particles > 0) o.pf.particles = options.adaptive_initial_particles;
  o.pf.seed = out.draws[run].seed;
  o.pf.threads = 1;
  o.dkf.initial = out.draws[run].dkf_initial;
  o.convergence_tolerance = out.convergence_tolerance;
  const calibration::CalibrationResult res = calibration::run_calibration({&in}, o);
  const calibration::TrackCalibrationScore& s = res.tracks.at(0);
  const FinalErrors e = final_errors(s);
  MethodRunResult& mr = row.runs[run];
  mr.err_rr_m = e.rr;
  mr.err_rl_m = e.rl;
  mr.err_d_m = e.d;
  mr.pose_rmse_m = s.pose_rmse_m;
  mr.heading_rmse_rad = s.heading_rmse_rad;
  mr.mean_particles = res.mean_particles;
  mr.ms_per_iteration = res.ms_per_iteration;
  if (row.online) {
    ParamTrace trace = param_trace(res, in);
    const std::vector<PieceConvergence> c = radius_convergence(trace, *in.truth, in.t.front(),
                                                               o.convergence_tolerance);
    mr.convergence_s = c.at(0).settled_s;
    mr.reached_s = c.at(0).reached_s;
    if (c.size() > 1) {
      mr.reconvergence_s = c[1].settled_s;
      mr.rereached_s = c[1].reached_s;
    }
    const bool pf = row.method == calibration::CalibrationMethod::adaptive_pf;
    auto& traces = pf ? (is_step ? out.pf_step : out.pf_constant) : (is_step ? out.dkf_step : out.dkf_constant);
    traces[run] = std::move(trace);
  }
}

// Each row's mean and standard deviation over its runs.
void summarise_rows(CalibrationStudy& out) {
  for (MethodRow& row : out.rows) {
    using R = MethodRunResult;
    row.err_rr_m = stat(row.runs, &R::err_rr_m);
    row.err_rl_m = stat(row.runs, &R::err_rl_m);
    row.err_d_m = stat(row.runs, &R::err_d_m);
    row.pose_rmse_m = stat(row.runs, &R::pose_rmse_m);
    row.heading_rmse_rad = stat(row.runs, &R::heading_rmse_rad);
    row.convergence_s = stat(row.runs, &R::convergence_s);
    row.reached_s = stat(row.runs, &R::reached_s);
    row.reconvergence_s = stat(row.runs, &R::reconvergence_s);
    row.rereached_s = stat(row.runs, &R::rereached_s);
    row.mean_particles = stat(row.runs, &R::mean_particles);
    row.ms_per_iteration = stat(row.runs, &R::ms_per_iteration);
  }
}

}  // namespace

CalibrationStudy run_calibration_study(const sim::Scenario& constant, const sim::Scenario& step,
                                       const StudyOptions& options, const StudyProgress& progress) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("study: " + why);
  check_study_scenario(constant, options);
  check_study_scenario(step, options);
  const auto t0 = std::chrono::steady_clock::now();

  CalibrationStudy out;
  out.scenario = constant.name;
  out.step_scenario = step.name;
  out.options = options;
  out.threads_used = threads_for(options);
  out.convergence_tolerance = calibration::CalibrationOptions{}.convergence_tolerance;
  set_up_rows(out, constant, options);

  const long row_count = static_cast<long>(out.rows.size());
  const long tasks = row_count * options.runs;
  const long total = options.runs + tasks;
  long done = 0;
  if (progress) progress(0, total);
  const std::vector<PreparedRun> runs = prepare_runs(constant, &step, out.draws, out.threads_used, &done, total,
                                                     progress);
  const std::vector<double> changes = runs.front().step.truth->change_times();
  if (!changes.empty()) out.step_time_s = changes.front();
  out.track_duration_s = runs.front().constant.t.back() - runs.front().constant.t.front();
  for (MethodRow& row : out.rows)
    row.has_step = row.track == StudyTrack::step && !runs.front().step.truth->change_times().empty();

  // The adaptive PF (the slowest) first in each run.
  parallel_tasks(tasks, out.threads_used, &done, total, progress,
                 [&](long k) { run_table2_task(out, runs, options, row_count, k); });
  summarise_rows(out);
  out.wall_s = seconds_since(t0);
  return out;
}

}  // namespace odotune::studies
