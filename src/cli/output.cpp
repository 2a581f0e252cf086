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
  j["improvement_pct"] = {
      {"rmse", improvement_pct(o.baseline_mean.rmse_m, o.tuned_mean.rmse_m)},
      {"mae", improvement_pct(o.baseline_mean.mae_m, o.tuned_mean.mae_m)},
      {"maxe", improvement_pct(o.baseline_mean.maxe_m, o.tuned_mean.maxe_m)}};
  j["baseline_fitness"] = o.baseline_fitness;
  j["tuned_fitness"] = o.tuned_fitness;
  j["evaluations"] = o.summary.evaluations;
  j["seconds"] = o.summary.seconds;
  j["termination"] = o.summary.termination;
  j["divergences"] = {{"non_finite", o.divergences.non_finite},
                      {"covariance_not_pd", o.divergences.covariance_not_pd}};
  nlohmann::json tracks = nlohmann::json::array();
  for (const auto& t : o.tracks)
    tracks.push_back({{"track", t.track}, {"baseline", metrics_json(t.baseline)},
                      {"tuned", metrics_json(t.tuned)}});
  j["tracks"] = tracks;
  nlohmann::json log = nlohmann::json::array();
  for (const auto& r : o.summary.log)
    log.push_back({{"iteration", r.iteration}, {"evaluations", r.evaluations},
                   {"best_fitness", r.best_fitness}});
  j["convergence"] = log;
  return j;
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
