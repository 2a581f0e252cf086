#include <odotune/jobs/store_access.h>

#include <fmt/format.h>

#include <odotune/core/failure.h>
#include <odotune/formats/experiment_yaml.h>
#include <odotune/objectives/param_space.h>
#include <odotune/objectives/tuned_model.h>
#include <odotune/tracks/track_io.h>

namespace odotune::jobs {

std::unique_ptr<results::Store> open_store_for_reading(const std::filesystem::path& path) {
  try {
    auto store = std::make_unique<results::Store>(path);
    if (store->experiment().hash.empty())
      throw core::Failure(fmt::format("{}: not a results store of odotune grid (no experiment recorded)",
                                      path.string()));
    return store;
  } catch (const std::runtime_error& ex) {
    if (dynamic_cast<const core::Failure*>(&ex)) throw;
    throw core::Failure(ex.what());
  }
}

std::map<std::string, tracks::Track> experiment_tracks(const results::ExperimentInfo& info,
                                                       const std::vector<std::string>& extra_files) {
  std::vector<std::string> files;
  if (!info.file.empty()) {
    try {
      files = formats::parse_experiment(info.text, info.file).tracks;
    } catch (const core::Failure&) {
      // The tracks moved since the grid ran: only --track files are used.
    }
  }
  std::map<std::string, tracks::Track> out;
  for (auto& t : tracks::load_tracks(files)) out.insert_or_assign(t.name(), std::move(t));
  for (auto& t : tracks::load_tracks(extra_files)) out.insert_or_assign(t.name(), std::move(t));
  return out;
}

objectives::TunedModel run_model(const results::RunRecord& run) {
  objectives::TunedModel m;
  if (!objectives::parse_tuned_model(run.model, &m))
    throw core::Failure(fmt::format("run {}: unknown model '{}', expected {}", results::run_key(run), run.model,
                                    objectives::tuned_model_names()));
  return m;
}

objectives::TunedModel stored_model(const std::string& name) {
  objectives::TunedModel m;
  if (!objectives::parse_tuned_model(name, &m))
    throw core::Failure(fmt::format("the store's model '{}' is unknown, expected {}", name,
                                    objectives::tuned_model_names()));
  return m;
}

double run_param(const results::RunRecord& run, const std::string& name) {
  for (std::size_t i = 0; i < run.param_names.size() && i < run.params.size(); ++i)
    if (run.param_names[i] == name) return run.params[i];
  throw core::Failure(fmt::format("run {}: parameter {} is missing", results::run_key(run), name));
}

filters::NoiseParams run_noise(const results::RunRecord& run) {
  const objectives::TunedModel model = run_model(run);
  if (model.is_calibrator())
    throw core::Failure(fmt::format("run {}: model {} tuned a calibrator's settings, not EKF noise",
                                    results::run_key(run), run.model));
  if (model.is_ukf())
    throw core::Failure(fmt::format("run {}: model {} tuned the velocity-fusion UKF's noise, not EKF noise",
                                    results::run_key(run), run.model));
  if (!model.is_ekf())
    throw core::Failure(
        fmt::format("run {}: model {} tuned robot_localization's filter, not odotune's EKF noise",
                    results::run_key(run), run.model));
  const objectives::ParamSpace space = objectives::ParamSpace::for_model(model.noise());
  std::vector<double> physical(space.dim());
  for (std::size_t i = 0; i < space.dim(); ++i) physical[i] = run_param(run, space.params()[i].name);
  filters::NoiseParams noise = space.to_noise(physical);
  std::string why;
  if (!noise.IsValid(&why))
    throw core::Failure(fmt::format("run {}: invalid parameters: {}", results::run_key(run), why));
  return noise;
}

formats::UkfConfig run_ukf_config(const results::RunRecord& run) {
  if (!run_model(run).is_ukf())
    throw core::Failure(fmt::format("run {}: model {} is not the fusion UKF", results::run_key(run),
                                    run.model));
  const objectives::BoxSpace space = learned::ukf_space();
  formats::UkfConfig cfg;
  cfg.rate_hz = learned::FusionInputOptions{}.rate_hz;  // what ukf_fusion_input (grid) fuses at
  for (const auto& p : space.params()) cfg.params.push_back(run_param(run, p.name));
  std::string why;
  if (!formats::apply_ukf_config(cfg).IsValid(&why))
    throw core::Failure(fmt::format("run {}: invalid parameters: {}", results::run_key(run), why));
  return cfg;
}

}  // namespace odotune::jobs
