#include "cli/output.h"

#include <omp.h>

#include <csignal>

#include <fmt/format.h>

#include "cli/failure.h"
#include "tracks/track_io.h"

namespace odotune::cli {

nlohmann::json metrics_json(const ErrorMetrics& m) {
  return {{"rmse_m", m.rmse_m}, {"mae_m", m.mae_m}, {"maxe_m", m.maxe_m}, {"samples", m.samples}};
}

nlohmann::json tune_json(const TuneOutcome& o) {
  nlohmann::json j;
  j["model"] = std::string(filters::to_string(o.request.model));
  j["mode"] = o.request.mode;
  j["mode_name"] = fitness_mode_name(o.request.mode);
  j["solver"] = o.request.solver;
  j["seed"] = o.request.seed;
  if (o.request.solver == "pso") {
    j["particles"] = o.request.particles;
    j["iterations"] = o.request.iterations;
  }
  nlohmann::json params = nlohmann::json::object(), units = nlohmann::json::object();
  for (std::size_t i = 0; i < o.params.size(); ++i) {
    params[o.param_names[i]] = o.params[i];
    units[o.param_names[i]] = o.param_units[i];
  }
  j["params"] = params;
  j["param_units"] = units;
  j["baseline"] = metrics_json(o.baseline_mean);
  j["tuned"] = metrics_json(o.tuned_mean);
  j["improvement_pct"] = improvement_json(o.baseline_mean, o.tuned_mean);
  j["baseline_fitness"] = o.baseline_fitness;
  j["tuned_fitness"] = o.tuned_fitness;
  j["evaluations"] = o.summary.evaluations;
  j["seconds"] = o.summary.seconds;
  j["termination"] = o.summary.termination;
  j["divergences"] = {{"non_finite", o.divergences.non_finite},
                      {"covariance_not_pd", o.divergences.covariance_not_pd}};
  j["tracks"] = track_scores_json(o.tracks);
  j["convergence"] = convergence_json(o.summary);
  return j;
}

void put_tuned_params_json(nlohmann::json& j, const std::vector<std::string>& names,
                           const std::vector<std::string>& units, const std::vector<double>& tuned,
                           const std::vector<double>& defaults, bool default_kept) {
  nlohmann::json params = nlohmann::json::object(), unit = nlohmann::json::object(),
                 start = nlohmann::json::object();
  for (std::size_t i = 0; i < tuned.size(); ++i) {
    params[names[i]] = tuned[i];
    unit[names[i]] = units[i];
    start[names[i]] = defaults[i];
  }
  j["params"] = params;
  j["param_units"] = unit;
  j["default_params"] = start;
  j["default_kept"] = default_kept;
}

nlohmann::json improvement_json(const ErrorMetrics& baseline, const ErrorMetrics& tuned) {
  return {{"rmse", improvement_pct(baseline.rmse_m, tuned.rmse_m)},
          {"mae", improvement_pct(baseline.mae_m, tuned.mae_m)},
          {"maxe", improvement_pct(baseline.maxe_m, tuned.maxe_m)}};
}

nlohmann::json track_scores_json(const std::vector<TrackScore>& tracks) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& t : tracks)
    out.push_back({{"track", t.track}, {"baseline", metrics_json(t.baseline)},
                   {"tuned", metrics_json(t.tuned)}});
  return out;
}

nlohmann::json convergence_json(const tuner::Summary& summary) {
  nlohmann::json log = nlohmann::json::array();
  for (const auto& r : summary.log)
    log.push_back({{"iteration", r.iteration}, {"evaluations", r.evaluations},
                   {"best_fitness", r.best_fitness}});
  return log;
}

void print_tune_result(const ErrorMetrics& baseline_mean, const ErrorMetrics& tuned_mean,
                       const std::vector<TrackScore>& tracks,
                       const std::vector<std::string>& param_names,
                       const std::vector<double>& params, const tuner::Summary& summary,
                       long diverged) {
  fmt::print("  RMSE {}\n", metric_change(baseline_mean.rmse_m, tuned_mean.rmse_m));
  fmt::print("  MAE  {}\n", metric_change(baseline_mean.mae_m, tuned_mean.mae_m));
  fmt::print("  MAXE {}\n", metric_change(baseline_mean.maxe_m, tuned_mean.maxe_m));
  if (tracks.size() > 1)
    for (const auto& t : tracks)
      fmt::print("    {}: RMSE {}\n", t.track, metric_change(t.baseline.rmse_m, t.tuned.rmse_m));
  fmt::print("  params:");
  for (std::size_t i = 0; i < params.size(); ++i) fmt::print(" {}={:.6g}", param_names[i], params[i]);
  fmt::print("\n  {} evaluations in {:.2f} s ({}); diverged evaluations: {}\n", summary.evaluations,
             summary.seconds, summary.termination, diverged);
}

std::string metric_change(double baseline_m, double tuned_m) {
  return fmt::format("{:7.2f} → {:7.2f} mm  ({:+5.1f} %)", baseline_m * 1e3, tuned_m * 1e3,
                     improvement_pct(baseline_m, tuned_m));
}

std::vector<Track> load_tracks(const std::vector<std::string>& paths) {
  std::vector<Track> tracks;
  for (const auto& p : paths) {
    try {
      tracks.push_back(read_track(p));
    } catch (const TrackError& e) {
      throw Failure(e.what());
    }
  }
  return tracks;
}

void add_threads_option(CLI::App* sub, int* threads) {
  sub->add_option("--threads", *threads, "OpenMP threads (0 = all cores); results do not depend on it")
      ->check(CLI::NonNegativeNumber);
}

void apply_threads(int threads) {
  if (threads > 0) omp_set_num_threads(threads);
}

namespace {
std::atomic<bool> g_interrupted{false};
extern "C" void on_signal(int sig) {
  g_interrupted.store(true);
  std::signal(sig, SIG_DFL);  // a second signal ends the process
}
}  // namespace

InterruptGuard::InterruptGuard() {
  g_interrupted.store(false);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
}
InterruptGuard::~InterruptGuard() {
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
}
const std::atomic<bool>* InterruptGuard::flag() const { return &g_interrupted; }
bool InterruptGuard::raised() const { return g_interrupted.load(); }

}  // namespace odotune::cli
