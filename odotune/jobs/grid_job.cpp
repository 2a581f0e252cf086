#include <odotune/jobs/grid_job.h>

#include <algorithm>

#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/failure.h>
#include <odotune/jobs/calibration_tune_job.h>
#include <odotune/jobs/rl_job.h>
#include <odotune/jobs/tune_job.h>
#include <odotune/jobs/ukf_tune_job.h>
#include <odotune/tracks/track_io.h>

namespace odotune::jobs {

int stored_mode(const CellFitness& f) {
  if (const auto* m = std::get_if<objectives::FitnessMode>(&f)) return objectives::number(*m);
  return objectives::stored_mode(std::get<objectives::RlFitness>(f));
}

std::vector<GridCell> grid_cells(const formats::Experiment& e) {
  std::vector<CellFitness> all;
  if (e.robot_localization)
    all.assign(e.robot_localization->fitness.begin(), e.robot_localization->fitness.end());
  else
    all.assign(e.modes.begin(), e.modes.end());
  std::vector<GridCell> cells;
  for (auto model : e.models) {
    // A calibrator has no fitness mode: the first listed stands for all.
    const std::vector<CellFitness> modes = model.is_calibrator() ? std::vector<CellFitness>{all.front()} : all;
    for (std::size_t t = 0; t < e.tracks.size(); ++t)
      for (const CellFitness& mode : modes)
        for (auto seed : e.seeds) cells.push_back({model, {t}, t, false, mode, seed});
    if (!e.leave_one_out) continue;
    for (std::size_t h = 0; h < e.tracks.size(); ++h) {
      std::vector<std::size_t> others;
      for (std::size_t t = 0; t < e.tracks.size(); ++t)
        if (t != h) others.push_back(t);
      for (const CellFitness& mode : modes)
        for (auto seed : e.seeds) cells.push_back({model, others, h, true, mode, seed});
    }
  }
  return cells;
}

namespace {
results::Metrics to_metrics(const objectives::ErrorMetrics& m) { return {m.rmse_m, m.mae_m, m.maxe_m}; }
}  // namespace

std::vector<PreparedTrack> prepare_grid_tracks(const formats::Experiment& e) {
  std::vector<PreparedTrack> tracks;
  if (e.robot_localization) {
    // rl-ekf and rl-ukf stand alone (experiment_yaml.h): their tracks are bags,
    // read for the model's filter.
    for (const std::string& bag : e.tracks) {
      PreparedTrack p;
      p.name = std::filesystem::path(bag).stem().string();
      p.rl = std::make_shared<const RlLoaded>(
          load_rl(rl_source_of(*e.robot_localization, bag, e.models.front().rl_filter())));
      const double duration_s = static_cast<double>(p.rl->rec.end_ns - p.rl->rec.start_ns) * 1e-9;
      if (!(e.robot_localization->until_s < duration_s))
        throw core::Failure(
            fmt::format("{}: robot_localization.until_s {} s leaves nothing to score (the bag lasts "
                        "{:.1f} s); expected an earlier until_s",
                        bag, e.robot_localization->until_s, duration_s));
      tracks.push_back(std::move(p));
    }
    return tracks;
  }
  calibration::CalibrationInputOptions calibration_options;
  calibration_options.ext_from_gt_rate_hz = e.calibration.ext_from_gt_hz;
  for (const auto& t : tracks::load_tracks(e.tracks)) {
    PreparedTrack p;
    p.name = t.name();
    const bool fix_cv = std::any_of(e.modes.begin(), e.modes.end(),
                                    [](objectives::FitnessMode m) { return objectives::is_fix_cv(m); });
    if (e.has_ekf_models()) {
      try {
        p = fix_cv ? prepare_track_fix_cv(t) : prepare_track(t);
      } catch (const std::invalid_argument& ex) {
        throw core::Failure(ex.what());
      }
    }
    if (e.has_calibrator_models()) {
      try {
        p.calibration = calibration::build_calibration_input(t, calibration_options);
      } catch (const std::invalid_argument& ex) {
        throw core::Failure(fmt::format("{} (needed by the experiment's calibrator models)", ex.what()));
      }
      if (!p.calibration->has_gt)
        throw core::Failure(
            fmt::format("track '{}': no ground truth (gt_x, gt_y, gt_theta), needed by the experiment's "
                        "calibrator models to score the calibrated odometry",
                        t.name()));
    }
    if (e.has_ukf_models()) {
      try {
        p.fusion = ukf_fusion_input(t);
      } catch (const std::invalid_argument& ex) {
        throw core::Failure(fmt::format("{} (needed by the experiment's ukf model)", ex.what()));
      }
    }
    tracks.push_back(std::move(p));
  }
  return tracks;
}

results::RunRecord cell_record(const formats::Experiment& e, const std::vector<PreparedTrack>& tracks,
                               const GridCell& c) {
  results::RunRecord r;
  r.model = objectives::to_string(c.model);
  r.track = c.heldout ? "all-but-" + tracks[c.score_on].name : tracks[c.score_on].name;
  r.heldout_track = c.heldout ? tracks[c.score_on].name : "";
  r.mode = stored_mode(c.fitness);
  r.seed = c.seed;
  r.solver = e.solver.name();
  return r;
}

std::vector<std::size_t> pending_cells(const formats::Experiment& e, const std::vector<PreparedTrack>& tracks,
                                       const std::vector<GridCell>& cells, const results::Store& store) {
  const std::set<std::string> finished = store.finished_keys();
  std::vector<std::size_t> pending;
  for (std::size_t i = 0; i < cells.size(); ++i)
    if (!finished.count(results::run_key(cell_record(e, tracks, cells[i])))) pending.push_back(i);
  return pending;
}

namespace {

// The experiment's solver for a cell (its seed), shared by every model.
SolverSettings cell_solver(const formats::Experiment& e, const GridCell& c, const std::atomic<bool>* stop) {
  SolverSettings s;
  s.solver = e.solver;
  s.seed = c.seed;
  s.particles = e.particles;
  s.iterations = e.iterations;
  s.evaluations = e.evaluations;
  s.stop = stop;
  return s;
}

// The solver's part of a cell's record, the same for every model.
void set_solver_fields(results::RunRecord& r, const std::vector<std::string>& param_names,
                       const std::vector<double>& params, double best_fitness, const tuner::Summary& summary,
                       long diverged) {
  r.param_names = param_names;
  r.params = params;
  r.best_fitness = best_fitness;
  r.evaluations = summary.evaluations;
  r.seconds = summary.seconds;
  r.diverged = diverged;
  r.termination = summary.termination_text();
  for (const auto& rec : summary.log) r.convergence.push_back({rec.evaluations, rec.best_fitness});
}

std::optional<results::RunRecord> run_calibration_cell(const formats::Experiment& e,
                                                       const std::vector<PreparedTrack>& tracks,
                                                       const GridCell& c, const std::atomic<bool>* stop) {
  results::RunRecord r = cell_record(e, tracks, c);
  CalibrationTuneRequest req;
  req.model = c.model.calib();
  req.resampler = e.calibration.resampler;
  req.policy = e.calibration.policy;
  // The experiment file's 0 is the paper's count.
  if (e.calibration.particles > 0) req.pf_particles = e.calibration.particles;
  req.pf_seed = e.calibration.seed;
  static_cast<SolverSettings&>(req) = cell_solver(e, c, stop);
  std::vector<const calibration::CalibrationInput*> tune_on;
  for (auto t : c.tune_on) tune_on.push_back(&*tracks[t].calibration);
  const CalibrationTuneOutcome o = run_calibration_tune(tune_on, req);
  if (o.summary.termination == tuner::Termination::stopped) return std::nullopt;
  set_solver_fields(r, o.param_names, o.params, o.tuned_score, o.summary, o.failures);
  if (!c.heldout) {
    // Tuned on the scored track alone: its scores are the outcome's.
    r.baseline = to_metrics(o.baseline.tracks.at(0).errors);
    r.tuned = to_metrics(o.tuned.tracks.at(0).errors);
  } else {
    // The held-out track, calibrated from scratch with either setting (its
    // robot's default calibrator, the tuned settings applied to it).
    const calibration::CalibrationInput& held = *tracks[c.score_on].calibration;
    const filters::PfCalibratorParams base = default_calibrator(req, held.nominal);
    r.baseline = to_metrics(evaluate_calibrator({&held}, req.model, base).tracks.at(0).errors);
    r.tuned = to_metrics(evaluate_calibrator({&held}, req.model,
                                             calibration::apply_calibration_params(base, o.params))
                             .tracks.at(0)
                             .errors);
  }
  return r;
}

std::optional<results::RunRecord> run_ukf_cell(const formats::Experiment& e,
                                               const std::vector<PreparedTrack>& tracks, const GridCell& c,
                                               const std::atomic<bool>* stop) {
  results::RunRecord r = cell_record(e, tracks, c);
  UkfTuneRequest req;
  req.mode = std::get<objectives::FitnessMode>(c.fitness);
  static_cast<SolverSettings&>(req) = cell_solver(e, c, stop);
  std::vector<const learned::FusionInput*> tune_on;
  for (auto t : c.tune_on) tune_on.push_back(&*tracks[t].fusion);
  const UkfTuneOutcome o = run_ukf_tune(tune_on, req);
  if (o.summary.termination == tuner::Termination::stopped) return std::nullopt;
  set_solver_fields(r, o.param_names, o.params, o.tuned_fitness, o.summary, o.failures);
  // Scores on the cell's track (the tuned track itself, or the held-out
  // one): the fused pose's errors with the default and the tuned noise.
  const learned::FusionInput* score = &*tracks[c.score_on].fusion;
  r.baseline = to_metrics(ukf_track_errors({score}, o.default_settings).at(0));
  r.tuned = to_metrics(ukf_track_errors({score}, o.tuned_settings).at(0));
  return r;
}

results::Metrics to_metrics(const objectives::FixScore& s) { return {s.rmse_m, s.mae_m, s.maxe_m}; }

// robot_localization's EKF or UKF tuned on the bag before until_s; its scores are
// the GPS-outage protocol's errors after it (GPS fused until until_s, none
// after), with the file's own and the tuned settings.
std::optional<results::RunRecord> run_rl_cell(const formats::Experiment& e,
                                              const std::vector<PreparedTrack>& tracks, const GridCell& c,
                                              const std::atomic<bool>* stop) {
  const formats::ExperimentRl& x = *e.robot_localization;
  results::RunRecord r = cell_record(e, tracks, c);
  RlTuneRequest req;
  static_cast<SolverSettings&>(req) = cell_solver(e, c, stop);
  req.until_s = x.until_s;
  req.end_s = x.end_s;
  req.options.fitness = std::get<objectives::RlFitness>(c.fitness);
  req.options.space = x.space;
  req.options.input_covariances = x.input_covariances;
  req.options.outage_s = x.outage_s;
  req.options.outage_stride_s = x.outage_every_s;
  req.search = x.search;
  std::string why;
  if (!req.IsValid(&why)) throw core::Failure(why);
  const RlTuneOutcome o = tune_rl(*tracks[c.score_on].rl, req);
  if (o.summary.termination == tuner::Termination::stopped) return std::nullopt;
  set_solver_fields(r, o.param_names, o.factors, o.tuned_fitness, o.summary, o.diverged);
  for (const RlParamProfile& p : o.starts[o.written].profiles)
    r.param_ranges.push_back({p.lo, p.hi, p.determined});
  if (!o.baseline_judged || !o.tuned_judged)
    throw core::Failure("nothing to score after robot_localization.until_s");
  r.baseline = to_metrics(o.baseline_judged->outage);
  r.tuned = to_metrics(o.tuned_judged->outage);
  return r;
}

}  // namespace

std::optional<results::RunRecord> run_cell(const formats::Experiment& e,
                                           const std::vector<PreparedTrack>& tracks, const GridCell& c,
                                           const std::atomic<bool>* stop) {
  if (c.model.is_calibrator()) return run_calibration_cell(e, tracks, c, stop);
  if (c.model.is_ukf()) return run_ukf_cell(e, tracks, c, stop);
  if (c.model.is_rl()) return run_rl_cell(e, tracks, c, stop);
  results::RunRecord r = cell_record(e, tracks, c);
  TuneRequest req;
  req.model = c.model.noise();
  req.mode = std::get<objectives::FitnessMode>(c.fitness);
  static_cast<SolverSettings&>(req) = cell_solver(e, c, stop);
  std::vector<const PreparedTrack*> tune_on;
  for (auto t : c.tune_on) tune_on.push_back(&tracks[t]);
  const TuneOutcome o = run_tune(tune_on, req);
  if (o.summary.termination == tuner::Termination::stopped) return std::nullopt;
  set_solver_fields(r, o.param_names, o.params, o.summary.best_fitness, o.summary, o.divergences.total());
  // Scores on the cell's track: the tuned track itself, or the held-out one;
  // modes 8 and 9 score the held-out fixes (the track may have no ground truth).
  if (objectives::is_fix_cv(req.mode)) {
    const objectives::FixCvReplay& cv = *tracks[c.score_on].cv;
    r.baseline = to_metrics(cv.evaluate(objectives::baseline_noise()).heldout);
    r.tuned = to_metrics(cv.evaluate(o.noise).heldout);
    return r;
  }
  const auto& score = tracks[c.score_on].input;
  r.baseline = to_metrics(objectives::replay_ekf(score, objectives::baseline_noise()).outcome.metrics);
  r.tuned = to_metrics(objectives::replay_ekf(score, o.noise).outcome.metrics);
  return r;
}

WorkResult work_cells(const formats::Experiment& e, const std::vector<PreparedTrack>& tracks,
                      const std::vector<GridCell>& cells, const CellSource& source,
                      const std::atomic<bool>* stop) {
  WorkResult out;
  // Called under the lock: keeps the first failure and tells the source.
  const auto fail = [&](const std::string& line) {
    if (!out.failure.empty()) return;
    out.failure = line;
    if (source.failed) {
      try {
        source.failed(line);
      } catch (const std::exception&) {  // the failure is returned all the same
      }
    }
  };
#pragma omp parallel
  {
    while (true) {
      std::optional<std::size_t> k;
#pragma omp critical(odotune_grid)
      {
        try {
          if (out.failure.empty() && !(stop && stop->load())) k = source.next();
        } catch (const std::exception& ex) {
          fail(ex.what());
        }
      }
      if (!k) break;
      const GridCell& c = cells[*k];
      try {
        std::optional<results::RunRecord> r = run_cell(e, tracks, c, stop);
#pragma omp critical(odotune_grid)
        {
          if (!r) {
            ++out.abandoned;
          } else {
            try {
              source.finished(std::move(*r));
              ++out.ran;
            } catch (const std::exception& ex) {
              fail(ex.what());
            }
          }
        }
      } catch (const std::exception& ex) {
#pragma omp critical(odotune_grid)
        fail(fmt::format("run {}: {}", results::run_key(cell_record(e, tracks, c)), ex.what()));
      }
    }
  }
  return out;
}

GridOutcome run_grid(const formats::Experiment& e, results::Store& store, const std::atomic<bool>* stop,
                     const std::function<void(long, long)>& progress) {
  const std::vector<PreparedTrack> tracks = prepare_grid_tracks(e);
  const std::vector<GridCell> cells = grid_cells(e);
  const std::vector<std::size_t> pending = pending_cells(e, tracks, cells, store);
  GridOutcome out;
  out.total = static_cast<long>(cells.size());
  out.skipped = out.total - static_cast<long>(pending.size());
  if (progress) progress(out.skipped, out.total);

  std::size_t next = 0;
  long done = out.skipped;
  CellSource source;
  source.next = [&]() -> std::optional<std::size_t> {
    if (next == pending.size()) return std::nullopt;
    return pending[next++];
  };
  source.finished = [&](results::RunRecord&& r) {
    store.add(r);
    ++done;
    if (progress) progress(done, out.total);
  };
  const WorkResult w = work_cells(e, tracks, cells, source, stop);
  if (!w.failure.empty()) throw core::Failure(w.failure);
  out.ran = w.ran;
  out.abandoned = w.abandoned;
  return out;
}

std::unique_ptr<results::Store> open_grid_store(const formats::Experiment& e, const std::filesystem::path& path,
                                                bool allow_other, const std::string& code_version) {
  try {
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
    return std::make_unique<results::Store>(
        path,
        results::ExperimentInfo{e.name, e.text, results::experiment_hash(e.text), code_version,
                                std::filesystem::absolute(e.file).lexically_normal().string()},
        allow_other);
  } catch (const std::filesystem::filesystem_error& ex) {
    throw core::Failure(fmt::format("{}: cannot create the store's folder: {}", path.string(),
                                    ex.code().message()));
  } catch (const std::runtime_error& ex) {
    throw core::Failure(ex.what());
  }
}

}  // namespace odotune::jobs
