// write_rl_run (odotune/jobs/rl_job.h): a stored rl-ekf or rl-ukf run as the robot's
// own parameter file.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include <odotune/core/failure.h>
#include <odotune/jobs/rl_job.h>

namespace odotune::jobs {

void write_rl_run(const formats::Experiment& e, const results::RunRecord& run, const std::filesystem::path& out,
                  bool ros2, const std::string& provenance) {
  if (!e.robot_localization)
    throw core::Failure(fmt::format("{}: the experiment has no robot_localization section", e.file.string()));
  const formats::ExperimentRl& x = *e.robot_localization;
  const auto bag = std::find_if(e.tracks.begin(), e.tracks.end(), [&](const std::string& t) {
    return std::filesystem::path(t).stem().string() == run.track;
  });
  if (bag == e.tracks.end())
    throw core::Failure(fmt::format("run's bag '{}' is not among the experiment's tracks", run.track));
  // Read again as the grid read it, for the file and for navsat's rotation.
  objectives::TunedModel model;
  if (!objectives::parse_tuned_model(run.model, &model) || !model.is_rl())
    throw core::Failure(fmt::format("run of model '{}': expected rl-ekf or rl-ukf", run.model));
  const RlLoaded loaded = load_rl(rl_source_of(x, *bag, model.rl_filter()));
  const rlnode::RlParams& params = loaded.rec.params;
  rlnode::ReplaySettings s = rlnode::settings_of(params);
  std::string why;
  if (!objectives::apply_rl_factors(params, run.param_names, run.params, &s, &why))
    throw core::Failure(fmt::format("{}: cannot apply the run's factors: {}", x.params.string(), why));
  const double change = 100.0 * (run.tuned.rmse_m / run.baseline.rmse_m - 1.0);
  const std::string held_out = fmt::format(
      "Tuned on the first {} s of {} (fitness {}, {} process noise); scored after it{}, never seen by the tune:\n"
      "  GPS fused until {} s, none after: RMSE {} with the file's values -> {} tuned{}.\n",
      x.until_s, bag->c_str(),
      objectives::to_string(objectives::rl_fitness_of_mode(run.mode).value_or(objectives::RlFitness::outage)),
      objectives::to_string(x.space), x.end_s ? fmt::format(" until {} s", *x.end_s) : "", x.until_s,
      rmse_text(3, run.baseline.rmse_m), rmse_text(3, run.tuned.rmse_m),
      std::isfinite(change) ? fmt::format(" ({:+.0f} %)", change) : "");
  write_tuned_params(out, params, s, loaded.alignment, x.gps_heading_fit_s, ros2, provenance + "\n" + held_out);
}

}  // namespace odotune::jobs
