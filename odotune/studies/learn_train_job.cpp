// `odotune learn train` (odotune/studies/learn_job.h): the paper's velocity nets or
// correction nets chosen by cross-validation, the optional slip detector,
// the model file and the lines the command prints.
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <odotune/core/failure.h>
#include <odotune/core/output_paths.h>
#include <odotune/studies/learn_job.h>
#include <odotune/studies/learned_study.h>

namespace odotune::studies {

namespace {

using results::LearnedModelFile;

learned::LearnedValidation validation_for(const LearnTrainRequest& r) {
  if (r.validation) return *r.validation;
  if (r.target == learned::LearnedTarget::velocity) return learned::LearnedValidation::chronological;
  return r.tracks.size() >= 2 ? learned::LearnedValidation::recordings : learned::LearnedValidation::blocks;
}

void check_request(const LearnTrainRequest& r, learned::LearnedValidation validation) {
  core::check_output_file("--model-out", r.model_out);
  if (r.iterations < 1) throw core::Failure(fmt::format("--iterations {}: expected >= 1", r.iterations));
  const bool paper = r.target == learned::LearnedTarget::velocity;
  if (paper && validation == learned::LearnedValidation::blocks)
    throw core::Failure(
        "--validation blocks: the paper's velocity nets validate chronologically or on recordings");
  if (!paper && validation == learned::LearnedValidation::chronological)
    throw core::Failure("--validation chronological: correction nets are validated on whole recordings or time "
                        "blocks (--validation recordings|blocks)");
  if (paper && r.input && *r.input != tracks::OdometryInput::wheels)
    throw core::Failure(
        fmt::format("--input {} with --target velocity: the paper's nets read wheel increments; "
                    "train correction nets (--target correction) on a {}",
                    tracks::to_string(*r.input), tracks::to_string(*r.input)));
}

// The paper's nets (odotune/learned/learned_odometry.h).
void train_paper_nets(const LearnTrainRequest& r, const std::vector<learned::FusionInput>& tracks,
                      learned::LearnedValidation validation, LearnedModelFile& file, LearnTrainOutcome& out) {
  learned::LearnedTrainingOptions lo;
  lo.training = learn_training_options(r.seed, r.iterations, r.threads);
  lo.previous_noise_v = r.previous_noise >= 0.0 ? r.previous_noise : LearnedStudyOptions{}.previous_noise_v;
  lo.previous_noise_w = r.previous_noise >= 0.0 ? r.previous_noise : LearnedStudyOptions{}.previous_noise_w;
  lo.validation = validation;
  try {
    file.odometry = learned::train_learned_odometry(fusion_pointers(tracks), lo, &out.odometry);
  } catch (const std::invalid_argument& e) {
    throw core::Failure(fmt::format("learn train: {}", e.what()));
  }
  const learned::LearnedTrainingSummary& s = out.odometry;
  file.provenance.odometry = results::training_record(s.v, s.w, s.train_windows, s.validation_windows,
                                                      s.seconds);
}

// The cross-validation as the model file keeps it (provenance.selection).
nlohmann::json selection_json(const learned::SelectionSummary& s, learned::LearnedValidation validation,
                              double block_s) {
  const auto n = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  const learned::CandidateResult& c = s.candidates[s.chosen];
  const auto combo = static_cast<std::size_t>(s.combination);
  nlohmann::json folds = nlohmann::json::array();
  for (const learned::FoldMeasures& f : c.folds)
    folds.push_back(
        {{"units", f.units},
         {"v_mae", {n(f.v_mae[0]), n(f.v_mae[1])}},
         {"w_mae", {n(f.w_mae[0]), n(f.w_mae[1])}},
         {"pose_rmse_kinematic_m", {n(f.pose_rmse[0][0]), n(f.pose_rmse[0][1]), n(f.pose_rmse[0][2])}},
         {"pose_rmse_chosen_m", {n(f.pose_rmse[combo][0]), n(f.pose_rmse[combo][1]), n(f.pose_rmse[combo][2])}},
         {"iterations", {f.v_iteration, f.w_iteration}}});
  nlohmann::json tried = nlohmann::json::array();
  for (const learned::CandidateResult& r : s.candidates) {
    nlohmann::json scores = nlohmann::json::array();
    for (int k = 0; k < learned::kNetCombinations; ++k)
      scores.push_back(
          {{"combination", std::string(learned::to_string(static_cast<learned::NetCombination>(k)))},
           {"score", n(r.score[static_cast<std::size_t>(k)])},
           {"se", n(r.score_se[static_cast<std::size_t>(k)])},
           {"fold_scores", r.fold_scores[static_cast<std::size_t>(k)]},
           {"qualifies", static_cast<bool>(r.qualifies[static_cast<std::size_t>(k)])}});
    tried.push_back({{"settings", r.settings.label()}, {"scores", scores}});
  }
  nlohmann::json j = {{"validation", std::string(learned::to_string(validation))},
                      {"units", s.units},
                      {"folds", s.folds},
                      {"candidates", s.candidates.size()},
                      {"settings",
                       {{"units", c.settings.units},
                        {"window", c.settings.window},
                        {"weight_decay", c.settings.weight_decay},
                        {"features", std::string(learned::to_string(c.settings.features))}}},
                      {"combination", std::string(learned::to_string(s.combination))},
                      {"iterations", {s.v_iterations, s.w_iterations}},
                      {"gyro", s.gyro},
                      {"fold_measures", folds},
                      {"tried", tried}};
  if (validation == learned::LearnedValidation::blocks) j["block_s"] = block_s;
  return j;
}

// Correction nets (odotune/learned/odometry_selection.h).
void train_correction_nets(const LearnTrainRequest& r, const std::vector<learned::FusionInput>& tracks,
                           learned::LearnedValidation validation, const LearnProgress& progress,
                           LearnedModelFile& file, LearnTrainOutcome& out) {
  learned::SelectionOptions so = r.selection;
  so.training = learn_training_options(r.seed, r.iterations, r.threads);
  so.training.early_stopping_patience = r.selection.training.early_stopping_patience;
  so.validation = validation;
  std::string why;
  if (!so.IsValid(&why)) throw core::Failure(fmt::format("learn train: {}", why));
  learned::SelectionSummary s;
  try {
    file.odometry = learned::train_correction_odometry(fusion_pointers(tracks), so, &s, progress);
  } catch (const std::invalid_argument& e) {
    throw core::Failure(fmt::format("learn train: {}", e.what()));
  }
  file.provenance.odometry = results::training_record(s.v, s.w, s.train_windows, 0, s.seconds);
  file.provenance.selection = selection_json(s, validation, so.block_s);
  out.selection = std::move(s);
}

void train_detector(const LearnTrainRequest& r, const std::vector<learned::FusionInput>& slips,
                    LearnedModelFile& file, LearnTrainOutcome& out) {
  std::vector<learned::OdometrySeries> odo;
  for (const learned::FusionInput& in : slips) {
    check_model_fits(file, in, in.track_name, "being trained");
    odo.push_back(learned::run_learned_odometry(in, file.odometry));
  }
  learned::SlipTrainingOptions so;
  so.training = learn_training_options(r.seed, r.slip_iterations > 0 ? r.slip_iterations : r.iterations,
                                       r.threads);
  so.drive = learned::available_slip_drive(fusion_pointers(slips));
  learned::SlipTrainingSummary slip_summary;
  try {
    file.detector = learned::train_slip_detector(fusion_pointers(slips), odo, so, &slip_summary);
  } catch (const std::invalid_argument& e) {
    throw core::Failure(fmt::format("learn train: slip detector: {}", e.what()));
  }
  file.provenance.detector = results::training_record(slip_summary.v, slip_summary.w,
                                                      slip_summary.train_windows,
                                                      slip_summary.validation_windows, slip_summary.seconds);
  out.detector = slip_summary;
  out.detector_drive = so.drive;
}

}  // namespace

LearnTrainOutcome run_learn_train(const LearnTrainRequest& r, const LearnProgress& progress) {
  const learned::LearnedValidation validation = validation_for(r);
  check_request(r, validation);
  const std::vector<learned::FusionInput> tracks = load_fusion_inputs(r.tracks, r.rate_hz, false,
                                                                      "to learn odometry from", r.input);
  const std::vector<learned::FusionInput> slips = load_fusion_inputs(r.slip_tracks, r.rate_hz, false,
                                                                     "to train the slip detector on", r.input);
  LearnTrainOutcome out;
  LearnedModelFile file;
  if (r.target == learned::LearnedTarget::velocity) {
    const long total = slips.empty() ? 1 : 2;
    report_progress(progress, 0, total);
    train_paper_nets(r, tracks, validation, file, out);
    report_progress(progress, 1, total);
  } else {
    train_correction_nets(r, tracks, validation, progress, file, out);
  }
  if (!slips.empty()) train_detector(r, slips, file, out);

  results::LearnedModelProvenance& p = file.provenance;
  for (const learned::FusionInput& in : tracks) p.tracks.push_back(in.track_name);
  for (const learned::FusionInput& in : slips) p.slip_tracks.push_back(in.track_name);
  p.seed = r.seed;
  p.created_by = r.command;
  results::write_learned_model(r.model_out, file);

  std::vector<learned::SeriesErrors> kin_v, kin_w;
  for (const learned::FusionInput& in : tracks) {
    kin_v.push_back(learned::series_errors(in.v_kin, in.v_true, {}));
    kin_w.push_back(learned::series_errors(in.w_kin, in.w_true, {}));
  }
  out.tracks = tracks.size();
  out.slip_tracks = slips.size();
  out.input = file.odometry.input;
  out.kinematic_v_mae = pooled_mae(kin_v);
  out.kinematic_w_mae = pooled_mae(kin_w);
  out.target = file.odometry.target;
  out.validation = validation;
  out.v_beats_kinematic = file.odometry.v_beats_kinematic;
  out.w_beats_kinematic = file.odometry.w_beats_kinematic;
  out.model_out = r.model_out;
  return out;
}

namespace {

std::string ratio(double learned, double kinematic) {
  return std::isfinite(learned) && std::isfinite(kinematic) && kinematic > 0
             ? fmt::format("{:.2f}", learned / kinematic)
             : std::string("–");
}

void paper_lines(const LearnTrainOutcome& o, std::vector<std::string>& l) {
  const learned::LearnedTrainingSummary& s = o.odometry;
  l.push_back(fmt::format("learned odometry (the paper's velocity nets) trained on {} track{} ({} windows for "
                          "training, {} for validation; {:.1f} s)",
                          o.tracks, o.tracks == 1 ? "" : "s", s.train_windows, s.validation_windows,
                          s.seconds));
  l.push_back(fmt::format("  V net: MAE {:.4f} m/s (training), {:.4f} m/s (validation), {} iterations",
                          s.v.train_mae, s.v.validation_mae, s.v.iterations));
  l.push_back(fmt::format("  W net: MAE {:.4f} rad/s (training), {:.4f} rad/s (validation), {} iterations",
                          s.w.train_mae, s.w.validation_mae, s.w.iterations));
  l.push_back(fmt::format("  free-running on the {}: V {:.4f} against kinematic {:.4f} m/s; W {:.4f} against "
                          "{:.4f} rad/s",
                          o.validation == learned::LearnedValidation::recordings ? "held-out recordings"
                                                                                 : "validation steps",
                          s.v_restart_mae[static_cast<std::size_t>(s.v_restart)], s.v_kinematic_mae,
                          s.w_restart_mae[static_cast<std::size_t>(s.w_restart)], s.w_kinematic_mae));
}

void correction_lines(const LearnTrainOutcome& o, std::vector<std::string>& l) {
  const learned::SelectionSummary& s = *o.selection;
  const learned::CandidateResult& c = s.candidates[s.chosen];
  const auto combo = static_cast<std::size_t>(s.combination);
  l.push_back(fmt::format("learned odometry (correction nets on {}{}) trained on {} track{}: cross-validation "
                          "over {} {} in {} folds, {} candidate settings ({:.1f} s)",
                          tracks::to_string(o.input), s.gyro ? " and the gyro" : "", o.tracks,
                          o.tracks == 1 ? "" : "s", s.units.size(),
                          o.validation == learned::LearnedValidation::recordings ? "recordings" : "blocks",
                          s.folds, s.candidates.size(), s.seconds));
  if (s.combination == learned::NetCombination::kinematic)
    l.push_back(
        fmt::format("  no setting beat the kinematic odometry on every fold: the model is the kinematic "
                    "odometry (best tried: {}, both nets)",
                    c.settings.label()));
  else
    l.push_back(fmt::format("  chosen: {}; kept: {} ({} and {} iterations)", c.settings.label(),
                            learned::to_string(s.combination), s.v_iterations, s.w_iterations));
  const std::size_t shown = s.combination == learned::NetCombination::kinematic ? 3 : combo;
  l.push_back(fmt::format("  each fold judged by nets trained without it, learned ÷ kinematic ({}):",
                          learned::to_string(static_cast<learned::NetCombination>(shown))));
  for (const learned::FoldMeasures& f : c.folds) {
    const auto& p = f.pose_rmse[shown];
    const auto& k = f.pose_rmse[0];
    l.push_back(fmt::format("    {}: V MAE {}, W MAE {}; XY RMSE 10 s {}, 60 s {}, whole {}",
                            fmt::join(f.units, ", "), ratio(f.v_mae[1], f.v_mae[0]),
                            ratio(f.w_mae[1], f.w_mae[0]), ratio(p[0], k[0]), ratio(p[1], k[1]),
                            ratio(p[2], k[2])));
  }
}

}  // namespace

std::vector<std::string> learn_train_lines(const LearnTrainOutcome& o) {
  std::vector<std::string> l;
  if (o.selection)
    correction_lines(o, l);
  else
    paper_lines(o, l);
  l.push_back(fmt::format("  kinematic odometry on the same tracks: MAE {:.4f} m/s, {:.4f} rad/s",
                          o.kinematic_v_mae, o.kinematic_w_mae));
  if (o.detector)
    l.push_back(fmt::format(
        "slip detector ({} and the odometry) trained on {} track{} ({} + {} windows; {:.1f} s): variance MAE V "
        "{:.3g}, W {:.3g} (validation)",
        o.detector_drive == learned::SlipDrive::power      ? "motor power"
        : o.detector_drive == learned::SlipDrive::commands ? "the commands"
                                                           : "no drive signal",
        o.slip_tracks, o.slip_tracks == 1 ? "" : "s", o.detector->train_windows, o.detector->validation_windows,
        o.detector->seconds, o.detector->v.validation_mae, o.detector->w.validation_mae));
  l.push_back(fmt::format("model: {}", o.model_out));
  return l;
}

}  // namespace odotune::studies
