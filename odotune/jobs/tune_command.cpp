#include <odotune/jobs/tune_command.h>

#include <algorithm>
#include <exception>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/failure.h>
#include <odotune/formats/config_yaml.h>
#include <odotune/formats/pf_config_yaml.h>
#include <odotune/formats/ukf_config_yaml.h>
#include <odotune/jobs/calibration_tune_json.h>
#include <odotune/jobs/tune_json.h>
#include <odotune/jobs/ukf_tune_json.h>
#include <odotune/objectives/tuned_model.h>
#include <odotune/tracks/track_io.h>

namespace odotune::jobs {

namespace {

// Options that belong to one kind of model only, by flag, and whether given.
void check_options(const TuneCommandRequest& r) {
  const objectives::TunedModel& model = r.model;
  const std::vector<std::pair<const char*, bool>> ekf_only = {{"--mode", r.mode.has_value()}};
  const std::vector<std::pair<const char*, bool>> calibrator_only = {
      {"--resampler", r.resampler.has_value()},
      {"--policy", r.policy.has_value()},
      {"--pf-particles", r.pf_particles.has_value()},
      {"--pf-seed", r.pf_seed.has_value()},
      {"--ext-from-gt", r.ext_from_gt_hz.has_value()}};
  for (const auto& [opt, given] : model.is_calibrator() ? ekf_only : calibrator_only)
    if (given)
      throw core::Failure(fmt::format("{} applies to {} models only, not to --model {}", opt,
                                      model.is_calibrator() ? "the EKF and UKF (rq, alpha, gyro, ukf)"
                                                            : "the calibrator",
                                      objectives::to_string(model)));
}

// `prepare(track)` for each loaded track, its std::invalid_argument a Failure.
template <class Prepare>
auto prepare_tracks(const std::vector<tracks::Track>& tracks, Prepare prepare) {
  std::vector<decltype(prepare(tracks.front()))> out;
  for (const auto& t : tracks) {
    try {
      out.push_back(prepare(t));
    } catch (const std::invalid_argument& e) {
      throw core::Failure(e.what());
    }
  }
  return out;
}

template <class T>
std::vector<const T*> pointers(const std::vector<T>& v) {
  std::vector<const T*> out;
  for (const auto& x : v) out.push_back(&x);
  return out;
}

// The request's solver settings with its progress and stop (the tune's own
// request type extends SolverSettings).
template <class Request>
Request with_solver(const TuneCommandRequest& r) {
  Request req;
  static_cast<SolverSettings&>(req) = static_cast<const SolverSettings&>(r);
  return req;
}

// Runs the tune (its failures one-line Failures) and reports the outcome.
template <class Run>
TuneCommandOutcome run_and_report(const TuneCommandRequest& r, Run run) {
  TuneCommandOutcome out;
  try {
    out = run();
  } catch (const std::exception& e) {
    throw core::Failure(e.what());
  }
  if (r.report) r.report(out);
  return out;
}

void write_json(const TuneCommandRequest& r, const nlohmann::json& j) {
  if (!r.json_out.empty()) formats::write_file_atomically(r.json_out, j.dump(2) + "\n");
}

TuneCommandOutcome ekf_tune(const TuneCommandRequest& r, filters::NoiseModel model) {
  TuneRequest req = with_solver<TuneRequest>(r);
  req.model = model;
  const std::vector<tracks::Track> tracks = tracks::load_tracks(r.tracks);
  std::string no_gt;
  for (const tracks::Track& t : tracks)
    if (!t.has_gt()) no_gt += (no_gt.empty() ? "" : ", ") + t.name();
  std::string note;
  if (r.mode) {
    req.mode = *r.mode;
    if (!no_gt.empty() && !objectives::is_fix_cv(req.mode))
      throw core::Failure(
          fmt::format("--mode {} scores against ground truth, which {} has not; use --mode 8 or 9 "
                      "(cross-validation over the position fixes), or leave --mode out",
                      objectives::number(req.mode), no_gt));
  } else {
    req.mode = no_gt.empty() ? objectives::kDefaultFitnessMode : objectives::FitnessMode::fix_rmse;
    if (!no_gt.empty())
      note = fmt::format("no ground truth in {}: tuning by cross-validation over the position fixes, mode 8 "
                         "({}; mode 9 scores their predictive likelihood instead)",
                         no_gt, objectives::fitness_mode_name(objectives::FitnessMode::fix_rmse));
  }
  std::string why;
  if (!req.IsValid(&why)) throw core::Failure(why);

  const std::vector<PreparedTrack> prepared =
      objectives::is_fix_cv(req.mode)
          ? prepare_tracks(tracks, [&](const tracks::Track& t) { return prepare_track_fix_cv(t, r.fix_cv); })
          : prepare_tracks(tracks, prepare_track);
  TuneCommandOutcome result = run_and_report(r, [&] {
    TuneOutcome o = run_tune(pointers(prepared), req);
    o.note = note;
    return o;
  });
  const auto& out = std::get<TuneOutcome>(result);
  write_json(r, tune_json(out));
  if (!r.config_out.empty()) {
    formats::EkfConfig cfg;
    cfg.model = req.model;
    cfg.noise = out.noise;
    cfg.comment = fmt::format("tuned by odotune tune: model {}, mode {}, solver {}, seed {}",
                              objectives::to_string(r.model), objectives::number(req.mode), req.solver.name(),
                              req.seed);
    formats::write_ekf_config(cfg, r.config_out);
  }
  return result;
}

TuneCommandOutcome calibration_tune(const TuneCommandRequest& r, objectives::CalibratorModel model) {
  CalibrationTuneRequest req = with_solver<CalibrationTuneRequest>(r);
  req.model = model;
  // Flags not given keep CalibrationTuneRequest's defaults.
  if (r.resampler) req.resampler = *r.resampler;
  if (r.policy) req.policy = *r.policy;
  req.pf_particles = r.pf_particles;
  if (r.pf_seed) req.pf_seed = *r.pf_seed;
  std::string why;
  if (!req.IsValid(&why)) throw core::Failure(why);
  calibration::CalibrationInputOptions input_options;
  input_options.ext_from_gt_rate_hz = r.ext_from_gt_hz.value_or(0.0);
  if (!input_options.IsValid(&why)) throw core::Failure("--ext-from-gt: " + why);

  const std::vector<calibration::CalibrationInput> inputs = prepare_tracks(
      tracks::load_tracks(r.tracks), [&](const tracks::Track& t) {
        calibration::CalibrationInput in = calibration::build_calibration_input(t, input_options);
        if (!in.has_gt)
          throw core::Failure(fmt::format("track '{}': no ground truth (gt_x, gt_y, gt_theta): a calibrator's "
                                          "settings are scored by its calibrated odometry against it",
                                          t.name()));
        return in;
      });
  TuneCommandOutcome result = run_and_report(r, [&] { return run_calibration_tune(pointers(inputs), req); });
  const auto& out = std::get<CalibrationTuneOutcome>(result);
  write_json(r, calibration_tune_json(out, {input_options.ext_from_gt_rate_hz}));
  if (!r.config_out.empty()) {
    calibration::CalibrationOptions effective;
    effective.method = calibration_method(model);
    effective.pf = out.tuned_pf;
    const filters::PfCalibratorParams run_with = calibration::effective_pf_params(effective);
    formats::PfConfig cfg;
    cfg.method = effective.method;
    cfg.resampler = run_with.resampler;
    cfg.policy = run_with.policy;
    cfg.particles = run_with.particles;
    cfg.params = out.params;
    cfg.comment = fmt::format(
        "tuned by odotune tune: model {}, solver {}, seed {}, calibrator seed {}; score {:.6g} "
        "(paper's defaults {:.6g})",
        objectives::to_string(r.model), req.solver.name(), req.seed, req.pf_seed, out.tuned_score,
        out.baseline_score);
    formats::write_pf_config(cfg, r.config_out);
  }
  return result;
}

TuneCommandOutcome ukf_tune(const TuneCommandRequest& r) {
  UkfTuneRequest req = with_solver<UkfTuneRequest>(r);
  req.mode = r.mode.value_or(objectives::kDefaultFitnessMode);
  std::string why;
  if (!req.IsValid(&why)) throw core::Failure(why);

  const std::vector<learned::FusionInput> inputs = prepare_tracks(tracks::load_tracks(r.tracks),
                                                                  ukf_fusion_input);
  TuneCommandOutcome result = run_and_report(r, [&] { return run_ukf_tune(pointers(inputs), req); });
  const auto& out = std::get<UkfTuneOutcome>(result);
  const double rate_hz = 1.0 / inputs.front().dt_s;
  write_json(r, ukf_tune_json(out, rate_hz));
  if (!r.config_out.empty()) {
    formats::UkfConfig cfg;
    cfg.rate_hz = rate_hz;
    cfg.params = out.params;
    cfg.comment = fmt::format(
        "tuned by odotune tune: model ukf, mode {} ({}), solver {}, seed {}\n"
        "fused pose RMSE {:.2f} mm tuned vs {:.2f} mm with the defaults (mean over {} track{})",
        objectives::number(req.mode), objectives::fitness_mode_name(req.mode), req.solver.name(), req.seed,
        out.tuned_mean.rmse_m * 1e3, out.baseline_mean.rmse_m * 1e3, inputs.size(),
        inputs.size() == 1 ? "" : "s");
    formats::write_ukf_config(cfg, r.config_out);
  }
  return result;
}

}  // namespace

TuneCommandOutcome run_tune_command(const TuneCommandRequest& request) {
  const objectives::TunedModel& model = request.model;
  if (model.is_rl())
    throw core::Failure(
        fmt::format("--model {}: robot_localization's filters are tuned from their parameter file and "
                    "bag: odotune tune --rl-params FILE --bag BAG{}",
                    objectives::to_string(model),
                    model.rl_filter() == filters::rl::RlFilterType::ukf ? " --filter ukf" : ""));
  check_options(request);
  if (model.is_calibrator()) return calibration_tune(request, model.calib());
  if (model.is_ukf()) return ukf_tune(request);
  return ekf_tune(request, model.noise());
}

}  // namespace odotune::jobs
