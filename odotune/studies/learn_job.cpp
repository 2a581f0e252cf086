#include <odotune/studies/learn_job.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <odotune/core/failure.h>
#include <odotune/core/output_paths.h>
#include <odotune/formats/calibration_yaml.h>
#include <odotune/formats/config_yaml.h>
#include <odotune/learned/pose_fusion.h>
#include <odotune/studies/learned_study.h>
#include <odotune/studies/learned_study_outputs.h>
#include <odotune/tracks/track_io.h>

namespace odotune::studies {

namespace {

using results::LearnedModelFile;

std::string per_step_csv(const learned::FusionInput& in, const learned::OdometrySeries& lstm,
                         const learned::OdometrySeries& kin, const learned::PoseTrack& pl,
                         const learned::PoseTrack& pk) {
  const auto n = [](double v) { return std::isfinite(v) ? fmt::format("{}", v) : std::string(); };
  std::string s =
      "t_s,v_true,w_true,v_learned,w_learned,v_kinematic,w_kinematic,x_true,y_true,theta_true,x_learned,y_learned,"
      "theta_learned,x_kinematic,y_kinematic,theta_kinematic\n";
  for (std::size_t k = 0; k < in.size(); ++k)
    s += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", n(in.t[k]), n(in.v_true[k]),
                     n(in.w_true[k]), n(lstm.v[k]), n(lstm.w[k]), n(kin.v[k]), n(kin.w[k]), n(in.gt_x[k]),
                     n(in.gt_y[k]), n(in.gt_theta[k]), n(pl.x[k]), n(pl.y[k]), n(pl.theta[k]), n(pk.x[k]),
                     n(pk.y[k]), n(pk.theta[k]));
  return s;
}

// One line of errors: "  NAME  V MAE … θ RMSE … rad".
std::string errors_line(const char* name, const learned::OdometryErrors& e) {
  std::string windows;
  if (std::isfinite(e.xy_rmse_10s))
    windows = fmt::format(" (10 s {:.3f}, 60 s {:.3f})", e.xy_rmse_10s, e.xy_rmse_60s);
  return fmt::format(
      "  {:<10} V MAE {:.4f} RMSE {:.4f} m/s   W MAE {:.4f} RMSE {:.4f} rad/s   XY RMSE {:.3f} m{}   "
      "θ RMSE {:.4f} rad",
      name, e.v.mae, e.v.rmse, e.w.mae, e.w.rmse, e.xy.rmse, windows, e.theta.rmse);
}

nlohmann::json summary_json(const learned::LstmTrainingSummary& s) {
  const auto n = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  return {{"cost_before", n(s.initial_cost)},
          {"cost_after", n(s.final_cost)},
          {"mae_after", n(s.train_mae)},
          {"iterations", s.iterations},
          {"usable", s.usable}};
}

}  // namespace

// ---------------------------------------------------------------- shared pieces

std::vector<const learned::FusionInput*> fusion_pointers(const std::vector<learned::FusionInput>& v) {
  std::vector<const learned::FusionInput*> p;
  for (const auto& in : v) p.push_back(&in);
  return p;
}

std::vector<learned::FusionInput> load_fusion_inputs(const std::vector<std::string>& files, double rate_hz,
                                                     bool need_power, const char* purpose,
                                                     std::optional<tracks::OdometryInput> input,
                                                     double ext_from_gt_hz) {
  const std::vector<tracks::Track> tracks = tracks::load_tracks(files);
  learned::FusionInputOptions o;
  o.rate_hz = rate_hz;
  o.input = input;
  o.ext_from_gt_hz = ext_from_gt_hz;
  std::string why;
  if (!o.IsValid(&why)) throw core::Failure(fmt::format("--rate-hz {}: {}", rate_hz, why));
  std::vector<learned::FusionInput> out;
  for (std::size_t k = 0; k < tracks.size(); ++k) {
    try {
      out.push_back(learned::build_fusion_input(tracks[k], o));
    } catch (const std::invalid_argument& e) {
      throw core::Failure(fmt::format("{}: {}", files[k], e.what()));
    }
    const learned::FusionInput& in = out.back();
    if (!in.has_gt)
      throw core::Failure(
          fmt::format("{}: track '{}' has no ground truth (gt_x, gt_y, gt_theta); expected it {}", files[k],
                      in.track_name, purpose));
    if (need_power && !in.has_power)
      throw core::Failure(fmt::format("{}: track '{}' has no motor power (power_l, power_r); expected it {}",
                                      files[k], in.track_name, purpose));
  }
  return out;
}

learned::LstmTrainingOptions learn_training_options(std::uint64_t seed, int iterations, int threads,
                                                    learned::LstmTrainingOptions base) {
  learned::LstmTrainingOptions t = base;
  t.seed = seed;
  t.max_iterations = iterations;
  t.num_threads = threads;
  return t;
}

double pooled_mae(const std::vector<learned::SeriesErrors>& e) {
  double sum = 0.0;
  std::size_t n = 0;
  for (const learned::SeriesErrors& s : e)
    if (s.samples > 0) sum += s.mae * static_cast<double>(s.samples), n += s.samples;
  return n > 0 ? sum / static_cast<double>(n) : NAN;
}

LearnedModelFile load_learned_model(const std::string& path) {
  try {
    return results::read_learned_model(path);
  } catch (const std::invalid_argument& e) {
    throw core::Failure(e.what());
  }
}

void check_model_fits(const LearnedModelFile& m, const learned::FusionInput& in, const std::string& file,
                      const std::string& model) {
  std::string why;
  if (!learned::model_fits(m.odometry, in, &why))
    throw core::Failure(fmt::format("{}: {} (model {})", file, why, model));
}

// ---------------------------------------------------------------- eval

namespace {

// The steps --from and --until leave to score: [first, end).
std::pair<std::size_t, std::size_t> scored_span(const LearnEvalRequest& r, const learned::FusionInput& in) {
  std::size_t first = 0, end = in.size();
  while (r.from_s && first < end && in.t[first] < *r.from_s) ++first;
  while (r.until_s && end > first && in.t[end - 1] >= *r.until_s) --end;
  if (end - first < 2)
    throw core::Failure(
        fmt::format("--from/--until: {} step{} of track '{}' left to score; expected at least 2", end - first,
                    end - first == 1 ? "" : "s", in.track_name));
  return {first, end};
}

learned::OdometrySeries slice_odometry(const learned::OdometrySeries& s, std::size_t first, std::size_t end) {
  const auto cut = [&](const std::vector<double>& v) {
    return std::vector<double>(v.begin() + static_cast<std::ptrdiff_t>(first),
                               v.begin() + static_cast<std::ptrdiff_t>(end));
  };
  return {cut(s.v), cut(s.w)};
}

// Static odometry variances from an MAE, as a Gaussian's: σ = MAE·√(π/2).
std::vector<learned::OdometryMeasurement> measured(const learned::OdometrySeries& s, double mae_v,
                                                   double mae_w) {
  std::vector<learned::OdometryMeasurement> m(s.v.size());
  const double var_v = std::max(1e-8, mae_v * mae_v * std::numbers::pi / 2);
  const double var_w = std::max(1e-8, mae_w * mae_w * std::numbers::pi / 2);
  for (std::size_t k = 0; k < m.size(); ++k) m[k] = {s.v[k], s.w[k], var_v, var_w};
  return m;
}

// What the slip detector flags on the scored steps, and the learned
// odometry's error there and elsewhere (LearnEvalOutcome::Flags).
LearnEvalOutcome::Flags slip_flags(const learned::FusionInput& full, const learned::SlipDetectorModel& d,
                                   const learned::OdometrySeries& odo, std::size_t first, std::size_t end,
                                   nlohmann::json& j) {
  LearnEvalOutcome::Flags f;
  f.drive = d.drive;
  learned::SlipDetectorStepper stepper(&d);
  std::size_t n_in = 0, n_out = 0;
  for (std::size_t k = 1; k < end; ++k) {
    const auto var = stepper.step(full, k);
    if (k < first || !std::isfinite(full.v_true[k]) || !std::isfinite(full.w_true[k])) continue;
    const bool flagged = var[0] > d.flag_var_v || var[1] > d.flag_var_w;
    const double ev = std::abs(odo.v[k] - full.v_true[k]), ew = std::abs(odo.w[k] - full.w_true[k]);
    ++f.steps;
    if (flagged)
      ++f.flagged, ++n_in, f.v_in += ev, f.w_in += ew;
    else
      ++n_out, f.v_out += ev, f.w_out += ew;
  }
  const auto mean = [](double sum, std::size_t n) {
    return n > 0 ? sum / static_cast<double>(n) : std::nan("");
  };
  f.v_in = mean(f.v_in, n_in), f.w_in = mean(f.w_in, n_in);
  f.v_out = mean(f.v_out, n_out), f.w_out = mean(f.w_out, n_out);
  const auto n = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  j["slip_detector"] = {{"drive", std::string(learned::to_string(d.drive))},
                        {"steps", f.steps},
                        {"flagged", f.flagged},
                        {"v_abs_error_flagged", n(f.v_in)},
                        {"v_abs_error_other", n(f.v_out)},
                        {"w_abs_error_flagged", n(f.w_in)},
                        {"w_abs_error_other", n(f.w_out)}};
  return f;
}

// Each odometry fused with the track's fixes (odotune/learned/pose_fusion.h), the
// kinematic ones with the kinematic MAE of the model's validation as their
// variance (the learned ones' where the file has none).
void fuse_with_fixes(const LearnEvalRequest& r, const LearnedModelFile& m, const learned::FusionInput& in,
                     const learned::OdometrySeries& lstm, const learned::FusionInput* cal,
                     LearnEvalOutcome& out, nlohmann::json& j) {
  learned::PoseFusionOptions o;
  o.fix_sigma_m = r.fix_sigma_m;
  o.noise.use_external = false;  // the fixes are the other sensor here
  const learned::LearnedOdometryModel& mo = m.odometry;
  const double kv = mo.v_kinematic_mae > 0 ? mo.v_kinematic_mae : mo.v_validation_mae;
  const double kw = mo.w_kinematic_mae > 0 ? mo.w_kinematic_mae : mo.w_validation_mae;
  LearnEvalOutcome::Fused f;
  try {
    const learned::PoseFusionTrace tl = learned::replay_pose_fusion(
        in, measured(lstm, mo.v_validation_mae, mo.w_validation_mae), o);
    const learned::PoseFusionTrace tk = learned::replay_pose_fusion(
        in, measured(learned::kinematic_odometry(in), kv, kw), o);
    f.learned = learned::pose_fusion_errors(in, tl);
    f.kinematic = learned::pose_fusion_errors(in, tk);
    f.fixes = tl.fixes;
    if (cal)
      f.calibrated = learned::pose_fusion_errors(
          *cal, learned::replay_pose_fusion(*cal, measured(learned::kinematic_odometry(*cal), kv, kw), o));
  } catch (const std::invalid_argument& e) {
    out.not_fused = e.what();
    return;
  }
  const auto block = [](const objectives::ErrorMetrics& e) {
    return nlohmann::json{{"pos_rmse_m", e.rmse_m}, {"pos_mae_m", e.mae_m}, {"samples", e.samples}};
  };
  j["fused"] = {{"fixes", f.fixes}, {"learned", block(f.learned)}, {"kinematic", block(f.kinematic)}};
  if (f.calibrated) j["fused"]["calibrated"] = block(*f.calibrated);
  out.fused = f;
}

// The eval track laid out with the calibration file's kinematics.
learned::FusionInput calibrated_input(const LearnEvalRequest& r, const LearnedModelFile& m) {
  const formats::CalibrationFile cal = formats::read_calibration_file(r.calibration);
  if (cal.odometry != m.odometry.input)
    throw core::Failure(fmt::format("--calibration {}: it calibrates {} odometry, the model reads {}",
                                    r.calibration, tracks::to_string(cal.odometry),
                                    tracks::to_string(m.odometry.input)));
  learned::FusionInputOptions o;
  o.rate_hz = m.odometry.rate_hz;
  o.input = m.odometry.input;
  if (cal.odometry == tracks::OdometryInput::wheels)
    o.geometry = cal.params;
  else
    o.twist = cal.twist;
  try {
    return learned::build_fusion_input(tracks::load_tracks({r.track}).front(), o);
  } catch (const std::invalid_argument& e) {
    throw core::Failure(fmt::format("{}: {}", r.track, e.what()));
  }
}

}  // namespace

LearnEvalOutcome run_learn_eval(const LearnEvalRequest& r) {
  core::check_output_file("--json", r.json);
  core::check_output_file("--csv", r.csv);
  const LearnedModelFile m = load_learned_model(r.model);
  if (!r.calibration.empty())
    (void)formats::read_calibration_file(r.calibration);  // a bad file fails before the work
  const std::vector<learned::FusionInput> tracks = load_fusion_inputs(
      {r.track}, m.odometry.rate_hz, false, "to score the odometry against", m.odometry.input);
  check_model_fits(m, tracks.front(), r.track, r.model);
  const auto [first, end] = scored_span(r, tracks.front());
  const learned::OdometrySeries lstm_full = learned::run_learned_odometry(tracks.front(), m.odometry);
  const learned::FusionInput in = learned::slice_fusion_input(tracks.front(), first, end);
  const learned::OdometrySeries lstm = slice_odometry(lstm_full, first, end),
                                kin = learned::kinematic_odometry(in);
  const learned::PoseTrack pl = learned::dead_reckon(in, lstm.v, lstm.w),
                           pk = learned::dead_reckon(in, kin.v, kin.w);
  LearnEvalOutcome out;
  out.learned = learned::odometry_errors(in, lstm.v, lstm.w, {}, {}, {});
  out.kinematic = learned::odometry_errors(in, kin.v, kin.w, {}, {}, {});
  nlohmann::json j = {{"track", in.track_name},
                      {"file", r.track},
                      {"model", r.model},
                      {"rate_hz", m.odometry.rate_hz},
                      {"input", std::string(tracks::to_string(m.odometry.input))},
                      {"learned", flat_errors_json(out.learned)},
                      {"kinematic", flat_errors_json(out.kinematic)}};
  std::optional<learned::FusionInput> cal;
  if (!r.calibration.empty()) {
    cal = learned::slice_fusion_input(calibrated_input(r, m), first, end);
    out.calibrated = learned::odometry_errors(*cal, cal->v_kin, cal->w_kin, {}, {}, {});
    j["calibrated"] = flat_errors_json(*out.calibrated);
    j["calibration"] = r.calibration;
  }
  if (in.has_fixes) fuse_with_fixes(r, m, in, lstm, cal ? &*cal : nullptr, out, j);
  if (m.detector && m.detector->flag_var_v > 0 && m.detector->input == in.input)
    out.slip = slip_flags(tracks.front(), *m.detector, lstm_full, first, end, j);
  if (first > 0 || end < tracks.front().size()) j["span_s"] = {in.t.front(), in.t.back()};
  if (!r.csv.empty()) formats::write_file_atomically(r.csv, per_step_csv(in, lstm, kin, pl, pk));
  if (!r.json.empty()) formats::write_file_atomically(r.json, j.dump(2) + "\n");
  out.track_name = in.track_name;
  out.file = r.track;
  out.model = r.model;
  out.json = r.json;
  out.csv = r.csv;
  out.steps = in.size();
  out.rate_hz = m.odometry.rate_hz;
  out.v_beats_kinematic = m.odometry.v_beats_kinematic;
  out.w_beats_kinematic = m.odometry.w_beats_kinematic;
  return out;
}

namespace {

// The first line of eval and retrain for a model with a net that is the kinematics.
std::string no_gain_note(bool v_beats, bool w_beats) {
  return fmt::format("note: the model's {} did not beat the kinematic odometry in its training; {} the "
                     "kinematic odometry",
                     !v_beats && !w_beats ? "V and W nets"
                     : !v_beats           ? "V net"
                                          : "W net",
                     !v_beats && !w_beats ? "they are" : "it is");
}

}  // namespace

std::vector<std::string> learn_eval_lines(const LearnEvalOutcome& o) {
  std::vector<std::string> l;
  if (!o.v_beats_kinematic || !o.w_beats_kinematic)
    l.push_back(no_gain_note(o.v_beats_kinematic, o.w_beats_kinematic));
  l.push_back(fmt::format("track {} ({}), {} steps at {:g} Hz, model {}:", o.track_name, o.file, o.steps,
                          o.rate_hz, o.model));
  l.push_back(errors_line("learned", o.learned));
  l.push_back(errors_line("kinematic", o.kinematic));
  if (o.calibrated) l.push_back(errors_line("calibrated", *o.calibrated));
  if (o.fused)
    l.push_back(fmt::format("  fused with {} position fixes: XY RMSE learned {:.3f} m, kinematic {:.3f} m{}",
                            o.fused->fixes, o.fused->learned.rmse_m, o.fused->kinematic.rmse_m,
                            o.fused->calibrated
                                ? fmt::format(", calibrated {:.3f} m", o.fused->calibrated->rmse_m)
                                : std::string()));
  if (!o.not_fused.empty()) l.push_back("  not fused with the track's fixes: " + o.not_fused);
  if (o.slip)
    l.push_back(
        fmt::format("  slip detector ({}): flags {} of {} steps ({:.1f} %); learned odometry's mean |error| "
                    "there V {:.4f} m/s, W {:.4f} rad/s, elsewhere V {:.4f}, W {:.4f}",
                    learned::to_string(o.slip->drive), o.slip->flagged, o.slip->steps,
                    100.0 * static_cast<double>(o.slip->flagged) /
                        static_cast<double>(std::max<std::size_t>(1, o.slip->steps)),
                    o.slip->v_in, o.slip->w_in, o.slip->v_out, o.slip->w_out));
  if (!o.csv.empty()) l.push_back(fmt::format("csv: {}", o.csv));
  if (!o.json.empty()) l.push_back(fmt::format("json: {}", o.json));
  return l;
}

// ---------------------------------------------------------------- retrain

namespace {

// The fusion of a retraining run: the model's nets, its slip detector or
// static variances from the validation MAE, retraining every r.every samples.
learned::LearnedFusionOptions retrain_fusion_options(const LearnRetrainRequest& r, const LearnedModelFile& m,
                                                     bool detector) {
  learned::LearnedFusionOptions o;
  o.odometry = learned::LearnedFusionOptions::Odometry::learned;
  o.detector = detector ? &*m.detector : nullptr;
  // Without a detector: a Gaussian's variance from the validation MAE, σ = MAE·√(π/2).
  o.static_var_v = std::max(1e-8,
                            m.odometry.v_validation_mae * m.odometry.v_validation_mae * std::numbers::pi / 2);
  o.static_var_w = std::max(1e-8,
                            m.odometry.w_validation_mae * m.odometry.w_validation_mae * std::numbers::pi / 2);
  o.retrain.samples_per_retrain = r.every;
  o.retrain.training = learn_training_options(m.provenance.seed, r.iterations, r.threads,
                                              learned::default_retrain_training());
  return o;
}

// The --json document: the run's settings, each retraining, and the errors
// with and without retraining.
nlohmann::json retrain_json(const LearnRetrainRequest& r, const learned::FusionInput& in, bool detector,
                            const learned::LearnedFusionResult& with,
                            const learned::LearnedFusionResult& without) {
  const auto block = [&](const learned::LearnedFusionResult& f) {
    learned::PoseTrack pose{f.filter.x, f.filter.y, f.filter.theta};
    return nlohmann::json{
        {"odometry", flat_errors_json(studies::odometry_only_errors(in, f.odometry))},
        {"filter", flat_errors_json(learned::odometry_errors(in, f.filter.v, f.filter.w, {}, {}, {}, &pose))},
        {"filter_healthy", f.filter.healthy}};
  };
  nlohmann::json events = nlohmann::json::array();
  for (const learned::RetrainEvent& e : with.retrains)
    events.push_back({{"step", e.step},
                      {"t_s", e.t_s},
                      {"ms", 1e3 * e.seconds},
                      {"v", summary_json(e.v)},
                      {"w", summary_json(e.w)}});
  return {{"track", in.track_name},
          {"file", r.track},
          {"model", r.model},
          {"covariance", detector ? "slip detector" : "static"},
          {"every", r.every},
          {"iterations", r.iterations},
          {"retrains", events},
          {"with_retraining", block(with)},
          {"without_retraining", block(without)}};
}

// The model with its nets as retraining left them, and its provenance.
void write_retrained_model(const LearnRetrainRequest& r, const LearnedModelFile& m,
                           const learned::FusionInput& in, const learned::LearnedFusionResult& with) {
  LearnedModelFile out = m;
  out.odometry = with.final_model.value_or(m.odometry);
  out.provenance.retrains += static_cast<int>(with.retrains.size());
  out.provenance.retrain_tracks.push_back(in.track_name);
  out.provenance.created_by = r.command;
  results::write_learned_model(r.model_out, out);
}

}  // namespace

LearnRetrainOutcome run_learn_retrain(const LearnRetrainRequest& r, const LearnProgress& progress) {
  core::check_output_file("--model-out", r.model_out);
  core::check_output_file("--json", r.json);
  if (r.every < 20) throw core::Failure(fmt::format("--every {}: expected >= 20 samples", r.every));
  if (r.iterations < 1) throw core::Failure(fmt::format("--iterations {}: expected >= 1", r.iterations));
  const LearnedModelFile m = load_learned_model(r.model);
  const bool detector = m.detector && !r.static_covariance;
  if (!(r.ext_from_gt_hz >= 0.0 && r.ext_from_gt_hz <= 100.0))
    throw core::Failure(fmt::format("--ext-from-gt {}: expected a rate in (0, 100] Hz", r.ext_from_gt_hz));
  const std::vector<learned::FusionInput> tracks = load_fusion_inputs(
      {r.track}, m.odometry.rate_hz, detector,
      "(the model's slip detector reads it; or give "
      "--static-covariance)",
      m.odometry.input, r.ext_from_gt_hz);
  check_model_fits(m, tracks.front(), r.track, r.model);
  std::size_t end = tracks.front().size();
  while (r.until_s && end > 0 && tracks.front().t[end - 1] >= *r.until_s) --end;
  if (end < 2)
    throw core::Failure(fmt::format("--until {}: no step of track '{}' before it", *r.until_s,
                                    tracks.front().track_name));
  const learned::FusionInput in = learned::slice_fusion_input(tracks.front(), 0, end);
  if (!in.has_ext)
    throw core::Failure(fmt::format(
        "{}: track '{}' has no external velocities (v_ext, w_ext); expected them, or --ext-from-gt HZ "
        "to derive them from its ground truth: the UKF retrains on its fused velocities",
        r.track, in.track_name));

  learned::LearnedFusionOptions o = retrain_fusion_options(r, m, detector);
  report_progress(progress, 0, 2);
  learned::LearnedFusionResult with, without;
  try {
    o.retrain.enabled = true;
    with = learned::run_learned_fusion(in, &m.odometry, o);
    report_progress(progress, 1, 2);
    o.retrain.enabled = false;
    without = learned::run_learned_fusion(in, &m.odometry, o);
    report_progress(progress, 2, 2);
  } catch (const std::invalid_argument& e) {
    throw core::Failure(fmt::format("learn retrain: {}", e.what()));
  }
  const nlohmann::json j = retrain_json(r, in, detector, with, without);
  if (!r.model_out.empty()) write_retrained_model(r, m, in, with);
  if (!r.json.empty()) formats::write_file_atomically(r.json, j.dump(2) + "\n");

  LearnRetrainOutcome out;
  out.track_name = in.track_name;
  out.file = r.track;
  out.model_out = r.model_out;
  out.json = r.json;
  out.every = r.every;
  out.iterations = r.iterations;
  out.detector = detector;
  out.v_beats_kinematic = m.odometry.v_beats_kinematic;
  out.w_beats_kinematic = m.odometry.w_beats_kinematic;
  out.gate = o.retrain;
  out.retrains = with.retrains;
  out.retrained = odometry_only_errors(in, with.odometry);
  out.fixed = odometry_only_errors(in, without.odometry);
  return out;
}

std::vector<std::string> learn_retrain_lines(const LearnRetrainOutcome& o) {
  const std::size_t n = o.retrains.size();
  std::vector<std::string> l;
  if (!o.v_beats_kinematic || !o.w_beats_kinematic)
    l.push_back(no_gain_note(o.v_beats_kinematic, o.w_beats_kinematic));
  l.push_back(fmt::format("track {} ({}): {} retrain{} every {} samples ({} iterations each), {} covariance",
                          o.track_name, o.file, n, n == 1 ? "" : "s", o.every, o.iterations,
                          o.detector ? "slip-detector" : "static"));
  if (o.retrains.empty())
    l.push_back(
        fmt::format("  no retrain: fewer than {} steps had filter variances below {:g}/{:g} and odometry "
                    "variances below {:g}/{:g} (V/W) — the retraining gate of paper §4.2",
                    o.every, o.gate.max_filter_var_v, o.gate.max_filter_var_w, o.gate.max_odometry_var_v,
                    o.gate.max_odometry_var_w));
  for (const learned::RetrainEvent& e : o.retrains)
    l.push_back(
        fmt::format("  t = {:8.2f} s (step {:5}): {:7.1f} ms; V cost {:.4g} → {:.4g} (MAE {:.4f} m/s), W cost "
                    "{:.4g} → {:.4g} (MAE {:.4f} rad/s)",
                    e.t_s, e.step, 1e3 * e.seconds, e.v.initial_cost, e.v.final_cost, e.v.train_mae,
                    e.w.initial_cost, e.w.final_cost, e.w.train_mae));
  l.push_back("odometry fed to the UKF, against the ground truth:");
  l.push_back(errors_line("retrained", o.retrained));
  l.push_back(errors_line("fixed", o.fixed));
  if (!o.model_out.empty()) l.push_back(fmt::format("model: {}", o.model_out));
  if (!o.json.empty()) l.push_back(fmt::format("json: {}", o.json));
  return l;
}

}  // namespace odotune::studies
