#include <odotune/jobs/export_job.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/enum_names.h>
#include <odotune/core/failure.h>
#include <odotune/formats/config_yaml.h>
#include <odotune/formats/ukf_config_yaml.h>
#include <odotune/jobs/rl_job.h>
#include <odotune/jobs/store_access.h>
#include <odotune/objectives/process_noise_rate.h>
#include <odotune/objectives/replay_input.h>
#include <odotune/objectives/tuned_model.h>
#include <odotune/results/ros_export.h>

namespace odotune::jobs {

namespace {

// "model, track, mode, seed, heldout", for messages.
std::string key_list() {
  std::string out;
  for (RunKey k : kAllRunKeys) out += (out.empty() ? "" : ", ") + std::string(to_string(k));
  return out;
}

bool is_integer_key(RunKey key) { return key == RunKey::mode || key == RunKey::seed; }

// A run's value for a selection key, as the user writes it.
std::string field(const results::RunRecord& r, RunKey key) {
  switch (key) {
    case RunKey::model: return r.model;
    case RunKey::track: return r.track;
    case RunKey::mode: return std::to_string(r.mode);
    case RunKey::seed: return std::to_string(r.seed);
    case RunKey::heldout: break;
  }
  return r.heldout_track.empty() ? "none" : r.heldout_track;
}

// The distinct values of `key` among `runs`, sorted (numerically for integers).
std::string values_of(const std::vector<const results::RunRecord*>& runs, RunKey key) {
  std::vector<std::string> v;
  v.reserve(runs.size());
  for (const auto* r : runs) v.push_back(field(*r, key));
  std::sort(v.begin(), v.end(), [key](const std::string& a, const std::string& b) {
    if (is_integer_key(key) && a.size() != b.size()) return a.size() < b.size();
    return a < b;
  });
  v.erase(std::unique(v.begin(), v.end()), v.end());
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : ", ") + s;
  return out;
}

std::string describe(const std::vector<RunFilter>& filters, std::size_t upto) {
  std::string out;
  for (std::size_t i = 0; i < upto; ++i) out += (out.empty() ? "" : ",") + filters[i].text();
  return out;
}

// The names of the tracks the run was tuned on: its track, or for a
// leave-one-out run every track of the store's experiment but the held-out one.
std::vector<std::string> tuning_track_names(const results::RunRecord& run,
                                            const std::vector<results::RunRecord>& all) {
  if (run.heldout_track.empty()) return {run.track};
  std::set<std::string> names;
  for (const auto& r : all) names.insert(r.scored_track());
  names.erase(run.heldout_track);
  return {names.begin(), names.end()};
}

std::vector<objectives::ReplayInput> tuning_inputs(const results::Store& store, const results::RunRecord& run,
                                                   const std::vector<results::RunRecord>& all,
                                                   const std::vector<std::string>& extra_files) {
  const std::map<std::string, tracks::Track> tracks = experiment_tracks(store.experiment(), extra_files);
  std::vector<objectives::ReplayInput> inputs;
  for (const std::string& name : tuning_track_names(run, all)) {
    const auto it = tracks.find(name);
    if (it == tracks.end())
      throw core::Failure(
          fmt::format("run {}: track '{}' (needed for its odometry rate) is not where the experiment "
                      "file said; pass it with --track FILE",
                      results::run_key(run), name));
    try {
      inputs.push_back(objectives::build_replay_input_any(it->second));
    } catch (const std::invalid_argument& e) {
      throw core::Failure(e.what());
    }
  }
  return inputs;
}

std::string join_names(const std::vector<objectives::ReplayInput>& inputs) {
  std::string out;
  for (const auto& in : inputs) out += (out.empty() ? "" : ", ") + in.track_name;
  return out;
}

std::string alpha_mapping_note(filters::NoiseModel model, const objectives::ProcessNoiseRate& q,
                               const std::vector<objectives::ReplayInput>& inputs) {
  const bool gyro = model == filters::NoiseModel::gyro;
  return fmt::format(
      "Mapping from odotune's {} model (Kovacs et al. eq. 3-5{}) to robot_localization:\n"
      "  odotune adds R_k = V_k·diag(σl², σr²)·V_kᵀ at every odometry step k, with\n"
      "  σl² = (α1·l)² + (α2·(l−r))², σr² = (α1·r)² + (α2·(l−r))² for the step's wheel travel\n"
      "  l, r [m]{}. R_k depends on the motion and, through V_k, on the heading θ,\n"
      "  so it has no constant equivalent. Q here is its time average over the track(s) the run\n"
      "  was tuned on ({}), replaying the tuned filter (prediction and fix correction) and\n"
      "  taking V_k at the filter's heading before each step:\n"
      "    Q[i][i] = Σ_k R_k[i][i] / Σ (t_N − t_1),  i = x, y [m²/s], yaw [rad²/s]\n"
      "  summed over steps 2..N of each track (t_k = time the odometry sample ending step k;\n"
      "  step 1 is left out, its start is unknown): {} steps over {:.6g} s, i.e. the mean\n"
      "  per-step R × {:.6g} Hz (the odometry rate). R is in m², rad² already (no mm² here).\n"
      "  R's off-diagonal terms (x–y, x–yaw, y–yaw) are dropped.\n"
      "  Heading dependence: in the world frame R puts along- and across-track wheel noise on\n"
      "  x and y according to θ; the average over the actual tracks is the honest constant for\n"
      "  motion like theirs (their mix of headings, speeds and turns), not for any motion.\n"
      "  (Alternatively, feed the wheel odometry as a twist input, odom0 vx/vyaw, and put the\n"
      "  wheel noise into that message's twist covariance.)\n"
      "  The fix variances below are the model's fixed σ = 60 mm (alpha/gyro do not tune q).",
      filters::to_string(model), gyro ? ", 6-7" : "",
      gyro ? ",\n  α1 = a1 + b1·|ω_z|, α2 = a2 + b2·|ω_z| with the step's |ω_z| (gyro, else odometry)" : "",
      join_names(inputs), q.steps, q.duration_s, q.odometry_rate_hz);
}

results::RosExportInput ros_input(const results::Store& store, const results::RunRecord& run,
                                  const std::vector<results::RunRecord>& all, const ExportRequest& request) {
  const filters::NoiseParams noise = run_noise(run);
  const std::vector<objectives::ReplayInput> inputs = tuning_inputs(store, run, all, request.track_files);
  results::RosExportInput in;
  try {
    if (noise.model == filters::NoiseModel::rq) {
      const double rate = objectives::odometry_rate_hz(inputs);
      in = results::ros_input_from_rq(run_param(run, "r1_mm2"), run_param(run, "r2_mm2"),
                                      run_param(run, "r3_rad2"), run_param(run, "q1_mm2"),
                                      run_param(run, "q2_mm2"), rate);
      in.provenance = fmt::format("odometry rate {:.6g} Hz measured on {}", rate, join_names(inputs));
    } else {
      const objectives::ProcessNoiseRate q = objectives::equivalent_process_noise_rate(noise, inputs);
      in.process_var_x_m2_per_s = q.x_m2_per_s;
      in.process_var_y_m2_per_s = q.y_m2_per_s;
      in.process_var_yaw_rad2_per_s = q.theta_rad2_per_s;
      in.fix_var_x_m2 = noise.q_x_m2;
      in.fix_var_y_m2 = noise.q_y_m2;
      in.frequency_hz = q.odometry_rate_hz;
      for (std::size_t i = 0; i < run.param_names.size() && i < run.params.size(); ++i)
        in.tuned_params.emplace_back(run.param_names[i], run.params[i]);
      in.mapping_note = alpha_mapping_note(noise.model, q, inputs);
    }
  } catch (const std::exception& e) {
    if (dynamic_cast<const core::Failure*>(&e)) throw;
    throw core::Failure(fmt::format("run {}: {}", results::run_key(run), e.what()));
  }
  in.node_name = request.node_name;
  return in;
}

}  // namespace

std::string_view to_string(ExportFormat f) {
  return f == ExportFormat::robot_localization ? "robot_localization" : "odotune";
}

bool parse_export_format(std::string_view text, ExportFormat* out) {
  return core::parse_by_name(text, kAllExportFormats, out);
}

std::string_view to_string(RunKey k) {
  switch (k) {
    case RunKey::model: return "model";
    case RunKey::track: return "track";
    case RunKey::mode: return "mode";
    case RunKey::seed: return "seed";
    case RunKey::heldout: return "heldout";
  }
  return "?";
}

bool parse_run_key(std::string_view text, RunKey* out) { return core::parse_by_name(text, kAllRunKeys, out); }

std::vector<RunFilter> parse_run_filters(const std::vector<std::string>& items) {
  std::vector<RunFilter> filters;
  for (const std::string& item : items) {
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == item.size())
      throw core::Failure(fmt::format("--select '{}': expected key=value with key one of {}", item,
                                      key_list()));
    RunFilter f{RunKey::model, item.substr(eq + 1)};
    if (!parse_run_key(item.substr(0, eq), &f.key))
      throw core::Failure(fmt::format("--select '{}': unknown key '{}', expected one of {}", item,
                                      item.substr(0, eq), key_list()));
    if (is_integer_key(f.key)) {
      std::uint64_t v = 0;
      const char* end = f.value.data() + f.value.size();
      const auto [ptr, ec] = std::from_chars(f.value.data(), end, v);
      if (ec != std::errc() || ptr != end)
        throw core::Failure(fmt::format("--select '{}': {} must be a non-negative integer", item,
                                        to_string(f.key)));
      f.value = std::to_string(v);
    }
    for (const RunFilter& g : filters)
      if (g.key == f.key && g.value != f.value)
        throw core::Failure(fmt::format("--select gives {} twice ({} and {}); give it once", to_string(f.key),
                                        g.value, f.value));
    filters.push_back(std::move(f));
  }
  return filters;
}

RunSelection select_best_run(const std::vector<results::RunRecord>& all, const std::vector<RunFilter>& filters,
                             const std::string& store) {
  if (all.empty()) throw core::Failure(fmt::format("{}: the store holds no finished runs yet", store));
  std::vector<const results::RunRecord*> runs;
  runs.reserve(all.size());
  for (const auto& r : all) runs.push_back(&r);
  for (std::size_t i = 0; i < filters.size(); ++i) {
    std::vector<const results::RunRecord*> kept;
    for (const auto* r : runs)
      if (field(*r, filters[i].key) == filters[i].value) kept.push_back(r);
    if (kept.empty())
      throw core::Failure(fmt::format("--select {}: no run matches{}; {} is one of: {}", filters[i].text(),
                                      i == 0 ? "" : " (with " + describe(filters, i) + ")",
                                      to_string(filters[i].key), values_of(runs, filters[i].key)));
    runs = std::move(kept);
  }
  std::set<std::string> models;
  for (const auto* r : runs) models.insert(r->model);
  if (models.size() > 1)
    throw core::Failure(fmt::format(
        "{} runs of {} models ({}); add --select model=… to pick one",
        filters.empty() ? "the store holds" : "--select " + describe(filters, filters.size()) + " matches",
        models.size(), values_of(runs, RunKey::model)));
  RunSelection s;
  s.matching = runs.size();
  if (run_model(*runs.front()).is_rl()) {
    // An rl-ekf or rl-ukf run's scores are on data its tune never saw: choosing by them
    // would make them optimistic, so the runs of one fitness are compared by
    // their tuning fitness instead.
    std::set<int> modes;
    for (const auto* r : runs) modes.insert(r->mode);
    if (modes.size() > 1)
      throw core::Failure(fmt::format("{} runs of {} fitnesses (modes {}); add --select mode=… to pick one (8 "
                                      "heldout-fixes, 10 outage, 11 both)",
                                      *models.begin(), modes.size(), values_of(runs, RunKey::mode)));
    for (const auto* r : runs)
      if (!s.run || r->best_fitness < s.run->best_fitness) s.run = r;
    return s;
  }
  for (const auto* r : runs)
    if (!s.run || r->tuned.rmse_m < s.run->tuned.rmse_m) s.run = r;
  return s;
}

ExportOutcome run_export(const ExportRequest& request) {
  const std::vector<RunFilter>& filters = request.select;
  const auto store = open_store_for_reading(request.store);
  const std::vector<results::RunRecord> all = store->runs();
  const RunSelection sel = select_best_run(all, filters, request.store);
  const results::RunRecord& run = *sel.run;
  const std::string key = results::run_key(run);
  const objectives::TunedModel model = run_model(run);
  if (model.is_calibrator())
    throw core::Failure(
        fmt::format("run {} tuned the {} calibrator's settings, not EKF noise: export writes EKF "
                    "configurations only; write a calibrator's settings with `odotune tune --model {} ... "
                    "--config-out FILE` (odotune-pf-config/1)",
                    key, run.model, run.model));
  if (model.is_ukf() && request.format != ExportFormat::odotune)
    throw core::Failure(
        fmt::format("run {} tuned the velocity-fusion UKF (model ukf): {} has no mapping for this model; "
                    "export it with --format odotune (odotune-ukf-config/1)",
                    key, to_string(request.format)));
  const std::string scores = fmt::format("tuned RMSE {:.2f} mm vs baseline {:.2f} mm on {}",
                                         run.tuned.rmse_m * 1e3, run.baseline.rmse_m * 1e3, run.scored_track());
  const std::string origin = fmt::format("odotune export from {} (experiment {}, {}): run {}", request.store,
                                         store->experiment().name, store->experiment().hash, key);

  if (model.is_rl()) {
    if (request.format != ExportFormat::robot_localization)
      throw core::Failure(
          fmt::format("run {} tuned robot_localization's {} (model {}): it exports as the robot's "
                      "own parameter file only; use --format robot_localization",
                      key, filters::rl::display_name(model.rl_filter()), run.model));
    const results::ExperimentInfo info = store->experiment();
    write_rl_run(formats::parse_experiment(info.text, info.file), run, request.out, !request.ros1,
                 origin + fmt::format("\nChosen as the lowest tuning fitness of {} matching run{}.",
                                      sel.matching, sel.matching == 1 ? "" : "s"));
    return {key,
            fmt::format("held-out GPS-outage RMSE {} vs {} with the file's values on {}",
                        rmse_text(3, run.tuned.rmse_m), rmse_text(3, run.baseline.rmse_m), run.track),
            sel.matching};
  }
  if (request.ros1)
    throw core::Failure(fmt::format("--ros1 applies to rl-ekf and rl-ukf runs only; run {} is of model {}", key,
                                    run.model));
  if (model.is_ukf()) {
    formats::UkfConfig cfg = run_ukf_config(run);
    cfg.comment = origin + "\n" + scores + " (the fused pose; baseline: the default UKF noise)";
    formats::write_ukf_config(cfg, request.out);
  } else if (request.format == ExportFormat::odotune) {
    formats::EkfConfig cfg;
    cfg.noise = run_noise(run);
    cfg.model = cfg.noise.model;
    cfg.comment = origin + "\n" + scores;
    formats::write_ekf_config(cfg, request.out);
  } else {
    results::RosExportInput in = ros_input(*store, run, all, request);
    in.provenance = origin + "; " + scores + (in.provenance.empty() ? "" : "; " + in.provenance);
    std::string why;
    if (!in.IsValid(&why)) throw core::Failure(fmt::format("run {}: cannot export: {}", key, why));
    try {
      results::write_robot_localization_yaml(in, request.out);
    } catch (const std::exception& e) {
      throw core::Failure(e.what());
    }
  }
  return {key, scores, sel.matching};
}

}  // namespace odotune::jobs
