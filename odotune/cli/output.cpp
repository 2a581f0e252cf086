#include <odotune/cli/output.h>

#include <omp.h>

#include <csignal>

#include <fmt/format.h>

#include <odotune/core/failure.h>
#include <odotune/tracks/track_io.h>

namespace odotune::cli {

void print_tune_result(const objectives::ErrorMetrics& baseline_mean,
                       const objectives::ErrorMetrics& tuned_mean, const std::vector<jobs::TrackScore>& tracks,
                       const std::vector<std::string>& param_names, const std::vector<double>& params,
                       const tuner::Summary& summary, long diverged) {
  fmt::print("  RMSE {}\n", metric_change(baseline_mean.rmse_m, tuned_mean.rmse_m));
  fmt::print("  MAE  {}\n", metric_change(baseline_mean.mae_m, tuned_mean.mae_m));
  fmt::print("  MAXE {}\n", metric_change(baseline_mean.maxe_m, tuned_mean.maxe_m));
  if (tracks.size() > 1)
    for (const auto& t : tracks)
      fmt::print("    {}: RMSE {}\n", t.track, metric_change(t.baseline.rmse_m, t.tuned.rmse_m));
  fmt::print("  params:");
  for (std::size_t i = 0; i < params.size(); ++i) fmt::print(" {}={:.6g}", param_names[i], params[i]);
  fmt::print("\n  {} evaluations in {:.2f} s ({}); diverged evaluations: {}\n", summary.evaluations,
             summary.seconds, summary.termination_text(), diverged);
}

void print_lines(const std::vector<std::string>& lines) {
  for (const std::string& l : lines) fmt::print("{}\n", l);
}

std::string metric_change(double baseline_m, double tuned_m) {
  return fmt::format("{:7.2f} → {:7.2f} mm  ({:+5.1f} %)", baseline_m * 1e3, tuned_m * 1e3,
                     objectives::improvement_pct(baseline_m, tuned_m));
}

CLI::Option* add_fitness_mode_option(CLI::App* sub, std::function<void(objectives::FitnessMode)> set,
                                     const std::string& help, bool ground_truth_only) {
  return sub->add_option_function<std::string>(
      "--mode",
      [set = std::move(set), ground_truth_only](const std::string& text) {
        objectives::FitnessMode m{};
        if (!objectives::parse_fitness_mode(text, &m) || (ground_truth_only && objectives::is_fix_cv(m)))
          throw CLI::ValidationError(fmt::format("--mode {} is out of range, expected {}", text,
                                                 objectives::fitness_mode_choices(ground_truth_only)));
        set(m);
      },
      help);
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
