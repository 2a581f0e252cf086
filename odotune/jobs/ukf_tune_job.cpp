#include <odotune/jobs/ukf_tune_job.h>

#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/why.h>
#include <odotune/objectives/ekf_objective.h>  // kDivergencePenalty
#include <odotune/tuner/problem.h>

namespace odotune::jobs {

bool UkfTuneRequest::IsValid(std::string* why) const {
  if (!SolverSettings::IsValid(why)) return false;
  if (objectives::is_fix_cv(mode)) {
    return core::invalid(why, fmt::format("mode = {} must be 1..7", objectives::number(mode)));
  }
  return true;
}

learned::FusionInput ukf_fusion_input(const tracks::Track& track) {
  learned::FusionInput in = learned::build_fusion_input(track);
  if (!in.has_gt)
    throw std::invalid_argument(fmt::format(
        "track '{}': no ground truth (gt_x, gt_y, gt_theta): the UKF's fused pose is scored against it",
        track.name()));
  return in;
}

std::vector<objectives::ErrorMetrics> ukf_track_errors(const std::vector<const learned::FusionInput*>& inputs,
                                                       const learned::UkfSettings& settings) {
  std::vector<objectives::ErrorMetrics> out;
  for (const learned::FusionInput* in : inputs) {
    bool healthy = true;
    objectives::ErrorMetrics m = learned::ukf_pose_errors(*in, settings, &healthy);
    if (!healthy) m.rmse_m = m.mae_m = m.maxe_m = objectives::kDivergencePenalty;
    out.push_back(m);
  }
  return out;
}

UkfTuneOutcome run_ukf_tune(const std::vector<const learned::FusionInput*>& inputs,
                            const UkfTuneRequest& request) {
  std::string why;
  if (!request.IsValid(&why)) throw std::invalid_argument(why);
  if (inputs.empty()) throw std::invalid_argument("no tracks to tune on");

  UkfTuneOutcome out;
  out.request = request;
  const learned::UkfObjective objective(inputs, request.mode, out.default_settings);
  const BoxProblem<learned::UkfObjective> problem{&objective};
  out.default_params = learned::ukf_params_of(out.default_settings);
  DefaultsTune t = run_solver_from_defaults(problem, request, objective.space(), out.default_params);
  out.param_names = std::move(t.param_names);
  out.param_units = std::move(t.param_units);
  out.summary = std::move(t.summary);
  out.baseline_fitness = t.baseline_fitness;
  out.default_kept = t.default_kept;
  out.tuned_fitness = t.tuned_fitness;
  out.params = std::move(t.params);
  out.tuned_settings = out.default_kept ? out.default_settings
                                        : learned::apply_ukf_params(out.default_settings, out.params);
  out.failures = objective.failures();

  const std::vector<objectives::ErrorMetrics> base = ukf_track_errors(inputs, out.default_settings);
  const std::vector<objectives::ErrorMetrics> tuned = ukf_track_errors(inputs, out.tuned_settings);
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    TrackScore score;
    score.track = inputs[i]->track_name;
    score.baseline = base[i];
    score.tuned = tuned[i];
    out.tracks.push_back(score);
  }
  out.baseline_mean = mean_metrics(base);
  out.tuned_mean = mean_metrics(tuned);
  return out;
}

}  // namespace odotune::jobs
