// run_rl_tune (jobs/rl_job.h): the search, its scores and the written file.
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/failure.h"
#include "core/output_paths.h"
#include "jobs/rl_job.h"

namespace odotune {
namespace {

namespace rl = filters::rl;

std::string score_text(const FixScore& s) { return s.finite ? fmt::format("{:.3f} m", s.rmse_m) : "diverged"; }

std::string percent(double before, double after) {
  return std::isfinite(before) && std::isfinite(after) && before > 0.0
             ? fmt::format("{:+.0f} %", 100.0 * (after / before - 1.0))
             : "n/a";
}

// The comment at the top of the written file: where it came from and what it
// scored (write_tuned_params adds navsat's rotation and the advice).
std::string provenance(const RlTuneRequest& r, const RlTuneOutcome& o) {
  std::string c = fmt::format(
      "Tuned by odotune (robot_localization's EKF replayed from the robot's bag).\n"
      "Command: {}\n"
      "Bag: {}; parameter file: {}\n"
      "Tuned on the first {:.1f} s of {:.1f} s: fitness {}, {} process noise{}, solver {} seed {}, {} replays.\n"
      "On the tuning span: held-out fixes {} -> {}; outages of {:.0f} s {} -> {}.\n",
      r.command_line.empty() ? "odotune tune --rl-params ..." : r.command_line, o.bag.string(),
      o.params_file.string(), o.span_s, o.duration_s, to_string(r.options.fitness), to_string(r.options.space),
      r.options.input_covariances ? " and input covariances" : "", r.solver.name(), r.seed,
      o.summary.evaluations, score_text(o.baseline_heldout), score_text(o.tuned_heldout), r.options.outage_s,
      score_text(o.baseline_outage), score_text(o.tuned_outage));
  if (o.baseline_after && o.tuned_after) {
    c += fmt::format("Held out (after {:.1f} s, never seen by the tune), file's values -> tuned:\n"
                     "  GPS outage from {:.1f} s: RMSE {} -> {} ({}); every 5th fix held out: {} -> {} ({}).\n",
                     o.span_s, o.span_s, score_text(o.baseline_after->outage),
                     score_text(o.tuned_after->outage),
                     percent(o.baseline_after->outage.rmse_m, o.tuned_after->outage.rmse_m),
                     score_text(o.baseline_after->every_fifth), score_text(o.tuned_after->every_fifth),
                     percent(o.baseline_after->every_fifth.rmse_m, o.tuned_after->every_fifth.rmse_m));
  }
  return c;
}

nlohmann::json json_of(const FixScore& s) {
  return {{"rmse_m", s.rmse_m}, {"fixes", s.fixes}, {"finite", s.finite}};
}

void write_json(const std::filesystem::path& path, const RlTuneRequest& r, const RlTuneOutcome& o) {
  nlohmann::json params = nlohmann::json::object();
  for (std::size_t i = 0; i < o.param_names.size(); ++i) params[o.param_names[i]] = o.factors[i];
  nlohmann::json j = {
      {"bag", o.bag.string()},
      {"params", o.params_file.string()},
      {"fitness", std::string(to_string(r.options.fitness))},
      {"space", std::string(to_string(r.options.space))},
      {"span_s", o.span_s},
      {"solver", r.solver.name()},
      {"seed", r.seed},
      {"evaluations", o.summary.evaluations},
      {"termination", o.summary.termination_text()},
      {"seconds", o.summary.seconds},
      {"factors", params},
      {"baseline_fitness", o.baseline_fitness},
      {"tuned_fitness", o.tuned_fitness},
      {"tuning_span",
       {{"baseline", {{"heldout_fixes", json_of(o.baseline_heldout)}, {"outage", json_of(o.baseline_outage)}}},
        {"tuned", {{"heldout_fixes", json_of(o.tuned_heldout)}, {"outage", json_of(o.tuned_outage)}}}}}};
  if (o.baseline_after) {
    j["held_out"] = {{"from_s", o.span_s},
                     {"baseline",
                      {{"outage", json_of(o.baseline_after->outage)},
                       {"every_fifth_fix", json_of(o.baseline_after->every_fifth)}}},
                     {"tuned",
                      {{"outage", json_of(o.tuned_after->outage)},
                       {"every_fifth_fix", json_of(o.tuned_after->every_fifth)}}}};
  }
  std::vector<double> diag(o.tuned.process_noise.diagonal().data(),
                           o.tuned.process_noise.diagonal().data() + 15);
  j["process_noise_diagonal"] = diag;
  write_atomically(path, "JSON", j.dump(2) + "\n");
}

}  // namespace

void write_tuned_params(const std::filesystem::path& path, const rlnode::RlParams& params,
                        const rlnode::ReplaySettings& tuned,
                        const std::optional<rlnode::GpsAlignment>& alignment, double fit_s, bool ros2,
                        std::string header) {
  rlnode::RlParamsUpdate update;
  update.process_noise_covariance = tuned.process_noise;
  if (alignment) {
    update.navsat_yaw_offset = alignment->yaw_offset_rad;
    header += fmt::format(
        "navsat_transform_node: the GPS-to-odom rotation was fitted on the first {:.0f} s ({:.4f} rad, residual "
        "{:.2f} m);\n  yaw_offset {:.4f} rad gives it with this IMU's heading at the first fix.\n",
        fit_s, alignment->transform.rotation_rad, alignment->rms_m, alignment->yaw_offset_rad);
  }
  bool advice = false;
  for (std::size_t s = 0; s < params.sensors.size(); ++s) {
    const double f = tuned.covariance_scale[s];
    if (std::abs(std::log10(f)) < 0.05) continue;
    if (!advice)
      header +=
          "Advised input covariances (the node reads them from the messages, so set them at the source):\n";
    advice = true;
    header += fmt::format(
        "  {} ({}): multiply its message covariance by {:.3g} (standard deviations by {:.3g})\n",
        params.sensors[s].name, params.sensors[s].topic, f, std::sqrt(f));
  }
  try {
    write_atomically(path, "parameter file",
                     rlnode::write_rl_params(params.file, params, update, ros2, header));
  } catch (const std::invalid_argument& e) {
    throw Failure(e.what());
  }
}

bool RlTuneRequest::IsValid(std::string* why) const {
  if (!SolverSettings::IsValid(why) || !options.IsValid(why)) return false;
  if (until_s && !(*until_s > 0.0)) {
    if (why) *why = fmt::format("--until {}: expected a positive number of seconds", *until_s);
    return false;
  }
  if (end_s && !(*end_s > until_s.value_or(0.0))) {
    if (why) *why = fmt::format("--end {}: expected more seconds than --until", *end_s);
    return false;
  }
  return true;
}

RlTuneOutcome tune_rl(const RlLoaded& loaded, const RlTuneRequest& request) {
  const rlnode::Recording& rec = loaded.rec;
  RlTuneOptions options = request.options;
  options.until_ns = request.until_s
                         ? rec.start_ns + static_cast<std::int64_t>(std::llround(*request.until_s * 1e9))
                         : std::numeric_limits<std::int64_t>::max();
  RlTuneOutcome o;
  o.bag = rec.bag;
  o.params_file = rec.params.file;
  o.duration_s = static_cast<double>(rec.end_ns - rec.start_ns) * 1e-9;
  o.span_s = request.until_s ? std::min(*request.until_s, o.duration_s) : o.duration_s;
  o.alignment = loaded.alignment;
  o.notes = rec.notes;
  o.baseline = rlnode::settings_of(rec.params);
  const RlObjective objective = [&] {
    try {
      return RlObjective(rec, o.baseline, options);
    } catch (const std::invalid_argument& e) {
      throw Failure(e.what());
    }
  }();
  const BoxProblem<RlObjective> problem{&objective};
  o.summary = run_solver(problem, request);
  o.diverged = objective.diverged();
  o.tuned = objective.settings_at(o.summary.best_x);
  for (const ParamSpec& p : objective.space().params()) o.param_names.push_back(p.name);
  o.factors = objective.space().to_physical(o.summary.best_x);
  o.tuned_fitness = o.summary.best_fitness;
  o.baseline_fitness = objective.baseline_fitness();
  o.baseline_heldout = objective.baseline_heldout();
  o.baseline_outage = objective.baseline_outage();
  o.tuned_heldout = objective.heldout_score(o.tuned);
  o.tuned_outage = objective.outage_score(o.tuned);
  // The held-out span: after --until, up to --end or the recording's end.
  const std::int64_t end_ns = request.end_s
                                  ? rec.start_ns + static_cast<std::int64_t>(std::llround(*request.end_s * 1e9))
                                  : std::numeric_limits<std::int64_t>::max();
  if (options.until_ns < std::min(rec.end_ns, end_ns)) {
    o.baseline_after = score_protocols(rec, o.baseline, options.until_ns, end_ns);
    o.tuned_after = score_protocols(rec, o.tuned, options.until_ns, end_ns);
  }
  return o;
}

RlTuneOutcome run_rl_tune(const RlTuneRequest& request) {
  std::string why;
  if (!request.IsValid(&why)) throw Failure("tune: " + why);
  check_output_file("--config-out", request.config_out.string());
  check_output_file("--json", request.json_out.string());
  check_output_file("--config-out-ros1", request.config_out_ros1.string());
  const RlLoaded loaded = load_rl(request.src);
  const rlnode::Recording& rec = loaded.rec;
  RlTuneOutcome o = tune_rl(loaded, request);
  const std::string header = provenance(request, o);
  for (const auto& [path, ros2] :
       {std::pair{request.config_out, !request.ros1_out}, std::pair{request.config_out_ros1, false}}) {
    if (!path.empty())
      write_tuned_params(path, rec.params, o.tuned, o.alignment, request.src.gps_heading_fit_s, ros2, header);
  }
  if (!request.json_out.empty()) write_json(request.json_out, request, o);
  return o;
}

}  // namespace odotune
