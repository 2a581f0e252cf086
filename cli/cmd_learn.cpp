// odotune learn train|eval|retrain: the learned odometry of Fariña, Acosta,
// Toledo & Acosta, "Improving Odometric Model Performance Based on LSTM
// Networks", Sensors 2023, 23, 961 (objectives/learned_odometry.h, the slip
// detector of objectives/slip_detector.h, the UKF fusion with online
// retraining of objectives/learned_fusion.h), on recorded or simulated tracks.
// This file reads the flags, checks the inputs, calls the objectives and
// prints; the model file is results/learned_model_json.h, the JSON blocks
// studies/learned_study_outputs.h.
#include <cmath>
#include <filesystem>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/commands.h"
#include "formats/config_yaml.h"
#include "core/failure.h"
#include "core/output_paths.h"
#include "studies/learned_study.h"
#include "studies/learned_study_outputs.h"
#include "cli/output.h"
#include "tracks/track_io.h"
#include "cli/progress.h"
#include "objectives/fusion_input.h"
#include "objectives/learned_fusion.h"
#include "objectives/learned_odometry.h"
#include "objectives/odometry_metrics.h"
#include "objectives/slip_detector.h"
#include "results/learned_model_json.h"

namespace odotune::cli {

namespace {

namespace fs = std::filesystem;
using results::LearnedModelFile;

struct LearnArgs {
  std::vector<std::string> tracks, slip_tracks;
  std::string track, model, model_out, json, csv;
  std::uint64_t seed = 1;
  int iterations = 100;          // train: Ceres iterations per velocity net
  int slip_iterations = 0;       // train: per detector net (0 = iterations)
  int retrain_iterations = 10;
  int every = 300;
  double rate_hz = 10.0;
  double previous_noise = -1.0;  // train: σ on the teacher-forced previous velocity; < 0 = the study's default
  int threads = 1;
  bool static_covariance = false;
};

// Loads tracks and lays them out for fusion; needs ground truth (and power).
std::vector<FusionInput> fusion_inputs(const std::vector<std::string>& files, double rate_hz, bool need_power,
                                       const char* purpose) {
  const std::vector<Track> tracks = load_tracks(files);
  FusionInputOptions o;
  o.rate_hz = rate_hz;
  std::string why;
  if (!o.IsValid(&why)) throw Failure(fmt::format("--rate-hz {}: {}", rate_hz, why));
  std::vector<FusionInput> out;
  for (std::size_t k = 0; k < tracks.size(); ++k) {
    try {
      out.push_back(build_fusion_input(tracks[k], o));
    } catch (const std::invalid_argument& e) {
      throw Failure(fmt::format("{}: {}", files[k], e.what()));
    }
    const FusionInput& in = out.back();
    if (!in.has_gt)
      throw Failure(fmt::format("{}: track '{}' has no ground truth (gt_x, gt_y, gt_theta); expected it {}", files[k],
                                in.track_name, purpose));
    if (need_power && !in.has_power)
      throw Failure(fmt::format("{}: track '{}' has no motor power (power_l, power_r); expected it {}", files[k],
                                in.track_name, purpose));
  }
  return out;
}

std::vector<const FusionInput*> pointers(const std::vector<FusionInput>& v) {
  std::vector<const FusionInput*> p;
  for (const auto& in : v) p.push_back(&in);
  return p;
}

// `base`: a fresh training's defaults, or default_retrain_training() for refits.
LstmTrainingOptions training_options(std::uint64_t seed, int iterations, int threads,
                                     LstmTrainingOptions base = {}) {
  LstmTrainingOptions t = base;
  t.seed = seed;
  t.max_iterations = iterations;
  t.num_threads = threads;
  return t;
}

// Pooled MAE of a series over several tracks (weighted by samples).
double pooled_mae(const std::vector<SeriesErrors>& e) {
  double sum = 0.0;
  std::size_t n = 0;
  for (const SeriesErrors& s : e)
    if (s.samples > 0) sum += s.mae * static_cast<double>(s.samples), n += s.samples;
  return n > 0 ? sum / static_cast<double>(n) : NAN;
}

LearnedModelFile read_model(const std::string& path) {
  try {
    return results::read_learned_model(path);
  } catch (const std::invalid_argument& e) {
    throw Failure(e.what());
  }
}

// The model and the track must describe the same robot and rate.
void check_model_fits(const LearnedModelFile& m, const FusionInput& in, const std::string& file,
                      const std::string& model) {
  if (std::abs(in.ticks_per_rev - m.odometry.ticks_per_rev) > 1e-9 * m.odometry.ticks_per_rev)
    throw Failure(fmt::format("{}: track '{}' has ticks_per_rev = {}, the model {} was trained with {}; expected the "
                              "same robot",
                              file, in.track_name, in.ticks_per_rev, model, m.odometry.ticks_per_rev));
}

// ---------------------------------------------------------------- train

void run_train(const LearnArgs& a, const std::string& command) {
  check_output_file("--model-out", a.model_out);
  if (a.iterations < 1) throw Failure(fmt::format("--iterations {}: expected >= 1", a.iterations));
  const std::vector<FusionInput> tracks = fusion_inputs(a.tracks, a.rate_hz, false, "to learn odometry from");
  const std::vector<FusionInput> slips =
      fusion_inputs(a.slip_tracks, a.rate_hz, true, "to train the slip detector on");

  Progress progress("learn train", "nets");
  const long total = slips.empty() ? 1 : 2;
  progress.update(0, total);
  LearnedTrainingOptions lo;
  lo.training = training_options(a.seed, a.iterations, a.threads);
  lo.previous_noise_v = a.previous_noise >= 0.0 ? a.previous_noise : LearnedStudyOptions{}.previous_noise_v;
  lo.previous_noise_w = a.previous_noise >= 0.0 ? a.previous_noise : LearnedStudyOptions{}.previous_noise_w;
  LearnedTrainingSummary summary;
  LearnedModelFile file;
  try {
    file.odometry = train_learned_odometry(pointers(tracks), lo, &summary);
  } catch (const std::invalid_argument& e) {
    throw Failure(fmt::format("learn train: {}", e.what()));
  }
  progress.update(1, total);
  SlipTrainingSummary slip_summary;
  if (!slips.empty()) {
    std::vector<OdometrySeries> odo;
    for (const FusionInput& in : slips) {
      check_model_fits(file, in, in.track_name, "being trained");
      odo.push_back(run_learned_odometry(in, file.odometry));
    }
    SlipTrainingOptions so;
    so.training = training_options(a.seed, a.slip_iterations > 0 ? a.slip_iterations : a.iterations, a.threads);
    try {
      file.detector = train_slip_detector(pointers(slips), odo, so, &slip_summary);
    } catch (const std::invalid_argument& e) {
      throw Failure(fmt::format("learn train: slip detector: {}", e.what()));
    }
    progress.update(2, total);
  }
  progress.finish();

  results::LearnedModelProvenance& p = file.provenance;
  for (const FusionInput& in : tracks) p.tracks.push_back(in.track_name);
  for (const FusionInput& in : slips) p.slip_tracks.push_back(in.track_name);
  p.seed = a.seed;
  p.odometry = results::training_record(summary.v, summary.w, summary.train_windows, summary.validation_windows,
                                        summary.seconds);
  if (file.detector)
    p.detector = results::training_record(slip_summary.v, slip_summary.w, slip_summary.train_windows,
                                          slip_summary.validation_windows, slip_summary.seconds);
  p.created_by = command;
  results::write_learned_model(a.model_out, file);

  std::vector<SeriesErrors> kin_v, kin_w;
  for (const FusionInput& in : tracks) {
    kin_v.push_back(series_errors(in.v_kin, in.v_true, {}));
    kin_w.push_back(series_errors(in.w_kin, in.w_true, {}));
  }
  fmt::print("learned odometry trained on {} track{} ({} windows for training, {} for validation; {:.1f} s)\n",
             tracks.size(), tracks.size() == 1 ? "" : "s", summary.train_windows, summary.validation_windows,
             summary.seconds);
  fmt::print("  V net: MAE {:.4f} m/s (training), {:.4f} m/s (validation), {} iterations\n", summary.v.train_mae,
             summary.v.validation_mae, summary.v.iterations);
  fmt::print("  W net: MAE {:.4f} rad/s (training), {:.4f} rad/s (validation), {} iterations\n", summary.w.train_mae,
             summary.w.validation_mae, summary.w.iterations);
  fmt::print("  kinematic odometry on the same tracks: MAE {:.4f} m/s, {:.4f} rad/s\n", pooled_mae(kin_v),
             pooled_mae(kin_w));
  if (file.detector)
    fmt::print("slip detector trained on {} track{} ({} + {} windows; {:.1f} s): variance MAE V {:.3g}, W {:.3g} "
               "(validation)\n",
               slips.size(), slips.size() == 1 ? "" : "s", slip_summary.train_windows, slip_summary.validation_windows,
               slip_summary.seconds, slip_summary.v.validation_mae, slip_summary.w.validation_mae);
  fmt::print("model: {}\n", a.model_out);
}

// ---------------------------------------------------------------- eval

std::string per_step_csv(const FusionInput& in, const OdometrySeries& lstm, const OdometrySeries& kin,
                         const PoseTrack& pl, const PoseTrack& pk) {
  const auto n = [](double v) { return std::isfinite(v) ? fmt::format("{}", v) : std::string(); };
  std::string s =
      "t_s,v_true,w_true,v_learned,w_learned,v_kinematic,w_kinematic,x_true,y_true,theta_true,x_learned,y_learned,"
      "theta_learned,x_kinematic,y_kinematic,theta_kinematic\n";
  for (std::size_t k = 0; k < in.size(); ++k)
    s += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", n(in.t[k]), n(in.v_true[k]), n(in.w_true[k]),
                     n(lstm.v[k]), n(lstm.w[k]), n(kin.v[k]), n(kin.w[k]), n(in.gt_x[k]), n(in.gt_y[k]),
                     n(in.gt_theta[k]), n(pl.x[k]), n(pl.y[k]), n(pl.theta[k]), n(pk.x[k]), n(pk.y[k]),
                     n(pk.theta[k]));
  return s;
}

void print_errors(const char* name, const OdometryErrors& e) {
  fmt::print("  {:<10} V MAE {:.4f} RMSE {:.4f} m/s   W MAE {:.4f} RMSE {:.4f} rad/s   XY RMSE {:.3f} m   θ RMSE "
             "{:.4f} rad\n",
             name, e.v.mae, e.v.rmse, e.w.mae, e.w.rmse, e.xy.rmse, e.theta.rmse);
}

void run_eval(const LearnArgs& a) {
  check_output_file("--json", a.json);
  check_output_file("--csv", a.csv);
  const LearnedModelFile m = read_model(a.model);
  const std::vector<FusionInput> tracks =
      fusion_inputs({a.track}, m.odometry.rate_hz, false, "to score the odometry against");
  const FusionInput& in = tracks.front();
  check_model_fits(m, in, a.track, a.model);
  const OdometrySeries lstm = run_learned_odometry(in, m.odometry);
  const OdometrySeries kin = kinematic_odometry(in);
  const PoseTrack pl = dead_reckon(in, lstm.v, lstm.w), pk = dead_reckon(in, kin.v, kin.w);
  const OdometryErrors el = odometry_errors(in, lstm.v, lstm.w, {}, {}, {}, &pl);
  const OdometryErrors ek = odometry_errors(in, kin.v, kin.w, {}, {}, {}, &pk);
  nlohmann::json j = {{"track", in.track_name}, {"file", a.track}, {"model", a.model},
                      {"rate_hz", m.odometry.rate_hz}, {"learned", flat_errors_json(el)},
                      {"kinematic", flat_errors_json(ek)}};
  if (!a.csv.empty()) write_file_atomically(a.csv, per_step_csv(in, lstm, kin, pl, pk));
  if (!a.json.empty()) write_file_atomically(a.json, j.dump(2) + "\n");
  fmt::print("track {} ({}), {} steps at {:g} Hz, model {}:\n", in.track_name, a.track, in.size(), m.odometry.rate_hz,
             a.model);
  print_errors("learned", el);
  print_errors("kinematic", ek);
  if (!a.csv.empty()) fmt::print("csv: {}\n", a.csv);
  if (!a.json.empty()) fmt::print("json: {}\n", a.json);
}

// ---------------------------------------------------------------- retrain

nlohmann::json summary_json(const LstmTrainingSummary& s) {
  const auto n = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  return {{"cost_before", n(s.initial_cost)}, {"cost_after", n(s.final_cost)}, {"mae_after", n(s.train_mae)},
          {"iterations", s.iterations}, {"usable", s.usable}};
}

void run_retrain(const LearnArgs& a, const std::string& command) {
  check_output_file("--model-out", a.model_out);
  check_output_file("--json", a.json);
  if (a.every < 20) throw Failure(fmt::format("--every {}: expected >= 20 samples", a.every));
  if (a.retrain_iterations < 1) throw Failure(fmt::format("--iterations {}: expected >= 1", a.retrain_iterations));
  LearnedModelFile m = read_model(a.model);
  const bool detector = m.detector && !a.static_covariance;
  const std::vector<FusionInput> tracks =
      fusion_inputs({a.track}, m.odometry.rate_hz, detector, "(the model's slip detector reads it; or give "
                                                             "--static-covariance)");
  const FusionInput& in = tracks.front();
  check_model_fits(m, in, a.track, a.model);
  if (!in.has_ext)
    throw Failure(fmt::format("{}: track '{}' has no external velocities (v_ext, w_ext); expected them: the UKF "
                              "retrains on its fused velocities",
                              a.track, in.track_name));

  LearnedFusionOptions o;
  o.odometry = LearnedFusionOptions::Odometry::learned;
  o.detector = detector ? &*m.detector : nullptr;
  // Without a detector: a Gaussian's variance from the validation MAE, σ = MAE·√(π/2).
  o.static_var_v = std::max(1e-8, m.odometry.v_validation_mae * m.odometry.v_validation_mae * std::numbers::pi / 2);
  o.static_var_w = std::max(1e-8, m.odometry.w_validation_mae * m.odometry.w_validation_mae * std::numbers::pi / 2);
  o.retrain.samples_per_retrain = a.every;
  o.retrain.training =
      training_options(m.provenance.seed, a.retrain_iterations, a.threads, default_retrain_training());

  Progress progress("learn retrain", "runs");
  progress.update(0, 2);
  LearnedFusionResult with, without;
  try {
    o.retrain.enabled = true;
    with = run_learned_fusion(in, &m.odometry, o);
    progress.update(1, 2);
    o.retrain.enabled = false;
    without = run_learned_fusion(in, &m.odometry, o);
    progress.update(2, 2);
  } catch (const std::invalid_argument& e) {
    throw Failure(fmt::format("learn retrain: {}", e.what()));
  }
  progress.finish();

  const auto block = [&](const LearnedFusionResult& r) {
    PoseTrack pose{r.filter.x, r.filter.y, r.filter.theta};
    return nlohmann::json{
        {"odometry", flat_errors_json(odometry_only_errors(in, r.odometry))},
        {"filter", flat_errors_json(odometry_errors(in, r.filter.v, r.filter.w, {}, {}, {}, &pose))},
        {"filter_healthy", r.filter.healthy}};
  };
  nlohmann::json events = nlohmann::json::array();
  for (const RetrainEvent& e : with.retrains)
    events.push_back({{"step", e.step}, {"t_s", e.t_s}, {"ms", 1e3 * e.seconds}, {"v", summary_json(e.v)},
                      {"w", summary_json(e.w)}});
  nlohmann::json j = {{"track", in.track_name},
                      {"file", a.track},
                      {"model", a.model},
                      {"covariance", detector ? "slip detector" : "static"},
                      {"every", a.every},
                      {"iterations", a.retrain_iterations},
                      {"retrains", events},
                      {"with_retraining", block(with)},
                      {"without_retraining", block(without)}};

  if (!a.model_out.empty()) {
    LearnedModelFile out = m;
    out.odometry = with.final_model.value_or(m.odometry);
    out.provenance.retrains += static_cast<int>(with.retrains.size());
    out.provenance.retrain_tracks.push_back(in.track_name);
    out.provenance.created_by = command;
    results::write_learned_model(a.model_out, out);
  }
  if (!a.json.empty()) write_file_atomically(a.json, j.dump(2) + "\n");

  fmt::print("track {} ({}): {} retrain{} every {} samples ({} iterations each), {} covariance\n", in.track_name,
             a.track, with.retrains.size(), with.retrains.size() == 1 ? "" : "s", a.every, a.retrain_iterations,
             detector ? "slip-detector" : "static");
  if (with.retrains.empty())
    fmt::print("  no retrain: fewer than {} steps had filter variances below {:g}/{:g} and odometry variances below "
               "{:g}/{:g} (V/W) — the retraining gate of paper §4.2\n",
               a.every, o.retrain.max_filter_var_v, o.retrain.max_filter_var_w, o.retrain.max_odometry_var_v,
               o.retrain.max_odometry_var_w);
  for (const RetrainEvent& e : with.retrains)
    fmt::print("  t = {:8.2f} s (step {:5}): {:7.1f} ms; V cost {:.4g} → {:.4g} (MAE {:.4f} m/s), W cost {:.4g} → "
               "{:.4g} (MAE {:.4f} rad/s)\n",
               e.t_s, e.step, 1e3 * e.seconds, e.v.initial_cost, e.v.final_cost, e.v.train_mae, e.w.initial_cost,
               e.w.final_cost, e.w.train_mae);
  fmt::print("odometry fed to the UKF, against the ground truth:\n");
  print_errors("retrained", odometry_only_errors(in, with.odometry));
  print_errors("fixed", odometry_only_errors(in, without.odometry));
  if (!a.model_out.empty()) fmt::print("model: {}\n", a.model_out);
  if (!a.json.empty()) fmt::print("json: {}\n", a.json);
}

}  // namespace

void register_learn(CLI::App& app) {
  auto* learn = app.add_subcommand(
      "learn", "Learned (LSTM) odometry with a slip detector and online retraining (Fariña et al., Sensors 2023)");
  learn->require_subcommand(1);
  learn->footer(
      "Examples:\n"
      "  odotune learn train --track a.csv --track b.csv --slip-track slip.csv --model-out model.json\n"
      "  odotune learn eval --track held_out.csv --model model.json --json eval.json\n"
      "  odotune learn retrain --track changed.csv --model model.json --model-out model2.json --json retrain.json");
  auto train = std::make_shared<LearnArgs>();
  auto* t = learn->add_subcommand("train", "Train the V and W nets (and the slip detector) on tracks with ground truth");
  t->add_option("--track", train->tracks, "track with ground truth (repeat for several)")->required();
  t->add_option("--slip-track", train->slip_tracks,
                "track with motor power and slip, to train the slip detector on (repeat for several)");
  t->add_option("--model-out", train->model_out, "model file to write (JSON, odotune-learned/1)")->required();
  t->add_option("--seed", train->seed, "seed of the initial weights")->default_val(train->seed);
  t->add_option("--iterations", train->iterations, "Ceres iterations per net")->default_val(train->iterations);
  t->add_option("--slip-iterations", train->slip_iterations,
                "Ceres iterations per slip-detector net (default: --iterations)")
      ->check(CLI::PositiveNumber);
  t->add_option("--previous-noise", train->previous_noise,
                "σ of the noise on the teacher-forced previous V [m/s] and W [rad/s] while training "
                "(default 0)")
      ->check(CLI::NonNegativeNumber);
  t->add_option("--rate-hz", train->rate_hz, "network rate [Hz] (paper: 10)")->default_val(train->rate_hz);
  t->add_option("--threads", train->threads, "threads evaluating the windows (results do not depend on it)")
      ->check(CLI::PositiveNumber);
  t->callback([train, t] {
    std::string c = "odotune learn train";
    for (const auto& f : train->tracks) c += " --track " + f;
    for (const auto& f : train->slip_tracks) c += " --slip-track " + f;
    c += " --model-out " + train->model_out + fmt::format(" --seed {} --iterations {}", train->seed, train->iterations);
    if (train->slip_iterations > 0) c += fmt::format(" --slip-iterations {}", train->slip_iterations);
    if (train->previous_noise >= 0.0) c += fmt::format(" --previous-noise {}", train->previous_noise);
    if (t->count("--rate-hz") > 0) c += fmt::format(" --rate-hz {}", train->rate_hz);
    run_train(*train, c);
  });

  auto eval = std::make_shared<LearnArgs>();
  auto* e = learn->add_subcommand("eval", "Score the learned and the kinematic odometry against a track's ground truth");
  e->add_option("--track", eval->track, "track with ground truth")->required();
  e->add_option("--model", eval->model, "model file (odotune learn train --model-out)")->required();
  e->add_option("--json", eval->json, "write the errors as JSON (blocks learned and kinematic)");
  e->add_option("--csv", eval->csv, "write the velocities and dead-reckoned poses per step as CSV");
  e->callback([eval] { run_eval(*eval); });

  auto retrain = std::make_shared<LearnArgs>();
  auto* r = learn->add_subcommand(
      "retrain", "Run the UKF with online retraining over a track (and without), compare, save the retrained model");
  r->add_option("--track", retrain->track, "track with ground truth and external velocities")->required();
  r->add_option("--model", retrain->model, "model file to start from")->required();
  r->add_option("--model-out", retrain->model_out, "write the retrained model here");
  r->add_option("--json", retrain->json, "write the retrain events and the errors with and without retraining");
  r->add_option("--every", retrain->every, "retrain every N well-localised samples (paper: 300)")
      ->default_val(retrain->every);
  r->add_option("--iterations", retrain->retrain_iterations, "Ceres iterations per refit")
      ->default_val(retrain->retrain_iterations);
  r->add_flag("--static-covariance", retrain->static_covariance,
              "ignore the model's slip detector: static odometry variances from the validation MAEs");
  r->add_option("--threads", retrain->threads, "threads evaluating the windows (results do not depend on it)")
      ->check(CLI::PositiveNumber);
  r->callback([retrain] {
    std::string c = "odotune learn retrain --track " + retrain->track + " --model " + retrain->model +
                    fmt::format(" --every {} --iterations {}", retrain->every, retrain->retrain_iterations);
    run_retrain(*retrain, c);
  });
}

}  // namespace odotune::cli
