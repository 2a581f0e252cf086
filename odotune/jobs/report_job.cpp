#include <odotune/jobs/report_job.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include <fmt/format.h>

#include <odotune/core/atomic_file.h>
#include <odotune/core/failure.h>
#include <odotune/jobs/report_writer.h>
#include <odotune/jobs/rl_job.h>
#include <odotune/jobs/store_access.h>
#include <odotune/objectives/metrics.h>
#include <odotune/objectives/param_space.h>
#include <odotune/objectives/replay.h>
#include <odotune/objectives/tuned_model.h>
#include <odotune/results/figures.h>
#include <odotune/results/report_html.h>
#include <odotune/results/report_tables.h>

namespace odotune::jobs {

namespace {

namespace fs = std::filesystem;
using results::ReportMetric;
using results::RunRecord;

// The run of `model` on `track` (per-track, mode `mode`) with the lowest
// tuned RMSE, or nullptr.
const RunRecord* best_run(const std::vector<RunRecord>& runs, const std::string& model,
                          const std::string& track, objectives::FitnessMode mode) {
  const RunRecord* best = nullptr;
  for (const auto& r : runs)
    if (!r.is_heldout() && r.model == model && r.track == track && r.mode == objectives::number(mode) &&
        (!best || r.tuned.rmse_m < best->tuned.rmse_m))
      best = &r;
  return best;
}

results::TrajectoryPath path_of(const std::string& name, const std::vector<objectives::TrajectoryPoint>& pts) {
  results::TrajectoryPath p{name, {}, {}};
  for (const auto& q : pts) {
    p.xs_m.push_back(q.x_m);
    p.ys_m.push_back(q.y_m);
  }
  return p;
}
// The store's runs and the names the report is drawn over, read and checked
// before anything is written; `store` stays open for the whole report. The
// store keeps each run's model as its name (the report's labels and file
// names); `kinds` is each of `models` parsed, once, where it is read.
struct CheckedStore {
  std::unique_ptr<results::Store> store;
  results::ExperimentInfo info;
  std::vector<RunRecord> runs;
  std::vector<std::string> models, tracks, overlay_tracks;
  std::vector<objectives::TunedModel> kinds;  // of `models`, in their order
};

// Checks the request (mode, store, track name, output folder) and reads the
// store; throws Failure with one line on the first problem.
CheckedStore open_checked(const ReportRequest& req) {
  CheckedStore s;
  s.store = open_store_for_reading(req.store);
  s.info = s.store->experiment();
  try {
    s.runs = s.store->runs();
  } catch (const std::exception& ex) {
    throw core::Failure(ex.what());
  }
  if (s.runs.empty())
    throw core::Failure(fmt::format("{}: no finished runs yet (run odotune grid first)", req.store.string()));
  s.models = results::report_models(s.runs);
  for (const std::string& m : s.models) s.kinds.push_back(stored_model(m));
  s.tracks = results::report_tracks(s.runs);
  for (const auto& t : s.tracks)
    if (req.trajectory_track.empty() || t == req.trajectory_track) s.overlay_tracks.push_back(t);
  if (s.overlay_tracks.empty())
    throw core::Failure(fmt::format("--track-name '{}' is not a track of this store, expected one of {}",
                                    req.trajectory_track, fmt::join(s.tracks, ", ")));
  std::error_code ec;
  fs::create_directories(req.out_dir, ec);
  if (ec || !fs::is_directory(req.out_dir))
    throw core::Failure(fmt::format("{}: cannot create the report folder: {}", req.out_dir.string(),
                                    ec ? ec.message() : "not a folder"));
  return s;
}

// The runs of the models named in `models`.
std::vector<RunRecord> runs_of(const std::vector<RunRecord>& from, const std::vector<std::string>& models) {
  std::vector<RunRecord> out_runs;
  for (const auto& r : from)
    if (std::find(models.begin(), models.end(), r.model) != models.end()) out_runs.push_back(r);
  return out_runs;
}

// What the sections of a (non-RL) report are drawn from: the checked store,
// its runs split into per-track (`own`) and held-out, and its models by kind.
struct ReportInput {
  const ReportRequest& req;
  const CheckedStore& s;
  std::vector<RunRecord> own, held;
  // Calibrator runs (pf-calib, adaptive-pf-calib; odotune/objectives/tuned_model.h) enter
  // the generic heatmaps, boxplots and tables; their baseline is the paper's
  // default PF settings and their metrics the calibrated odometry's dead
  // reckoning, so Table 1 and the convergence curves keep them apart from
  // the EKF models', and the EKF trajectory replay leaves them out.
  // The fusion UKF's runs (ukf) likewise have their own baseline (the
  // default UKF noise) and metrics (the fused pose's errors): their own
  // table, and no EKF trajectory replay.
  std::vector<std::string> ekf_models, calibrator_models, ukf_models;
};

ReportInput split_runs(const ReportRequest& req, const CheckedStore& s) {
  ReportInput in{req, s, {}, {}, {}, {}, {}};
  for (const auto& r : s.runs) (r.is_heldout() ? in.held : in.own).push_back(r);
  for (std::size_t k = 0; k < s.models.size(); ++k)
    (s.kinds[k].is_calibrator() ? in.calibrator_models
     : s.kinds[k].is_ukf()      ? in.ukf_models
                                : in.ekf_models)
        .push_back(s.models[k]);
  return in;
}

// The page's opening paragraphs: the experiment, and the calibrator and UKF
// models' different baselines when there are any.
void write_intro(const ReportInput& in, results::HtmlPage& page) {
  const CheckedStore& s = in.s;
  page.paragraph(
      fmt::format("Experiment **{}** (file hash {}, odotune {}): {} runs, {} of them leave-one-track-out; "
                  "models {}; tracks {}. Improvement % = 100 · (baseline − tuned) / baseline, positive is "
                  "better; the baseline is odotune's untuned configuration (README, \"Baseline\").",
                  s.info.name, s.info.hash, s.info.code_version, s.runs.size(), in.held.size(),
                  fmt::join(s.models, ", "), fmt::join(s.tracks, ", ")));
  if (!in.calibrator_models.empty())
    page.paragraph(
        fmt::format("Calibrator models ({}) tune the particle-filter calibrator's settings instead of EKF "
                    "noise: their baseline is the paper's default settings, their metrics the dead-reckoning "
                    "position errors of the calibrated odometry against ground truth, and they have runs for "
                    "one fitness mode only (the experiment's first; a calibrator has none).",
                    fmt::join(in.calibrator_models, ", ")));
  if (!in.ukf_models.empty())
    page.paragraph("The ukf model tunes the noise of the velocity-fusion UKF (Fariña et al., Sensors 2023, "
                   "23, 961, §1: odometry, external velocities and gyro fused on (V, W), the pose integrated "
                   "by eq. 3) instead of EKF noise: its baseline is the default UKF noise and its metrics "
                   "the fused pose's position errors against ground truth.");
}

// Headline: mean RMSE improvement per model over all per-track runs.
std::string headline(const ReportInput& in) {
  std::vector<std::string> parts;
  for (const auto& m : in.s.models) {
    double s = 0;
    int n = 0;
    for (const auto& r : in.own)
      if (r.model == m) s += r.improvement_rmse_pct(), ++n;
    if (n) parts.push_back(fmt::format("{} {:+.1f} %", m, s / n));
  }
  return fmt::format("mean RMSE improvement over the baseline: {}", fmt::join(parts, ", "));
}

// (a) Figure 3: heatmaps, per-track and held-out side by side.
void write_heatmaps(const ReportInput& in, ReportWriter& w, results::HtmlPage& page) {
  page.heading("Improvement over the baseline per fitness mode and track (Figure 3)");
  page.paragraph("Rows: fitness modes 1–7; columns: tracks; each cell the mean improvement over seeds. "
                 "Left: tuned and scored on the same track; right (when the experiment has "
                 "leave_one_out): tuned on all other tracks, scored on the column's track.");
  for (ReportMetric metric : results::kReportMetrics) {
    const std::string mname(results::metric_name(metric));
    for (const auto& model : in.s.models) {
      std::vector<results::HtmlFigure> row;
      for (bool heldout : {false, true}) {
        const auto grid = results::improvement_grid(in.s.runs, model, metric, heldout, in.s.tracks);
        if (grid.empty()) continue;
        const std::string name = fmt::format("heatmap_{}{}_{}", heldout ? "heldout_" : "", file_safe(model),
                                             lower(mname));
        const std::string title = fmt::format("{} improvement [%], {}{}", mname, model,
                                              heldout ? ", held out" : "");
        const std::string caption = fmt::format(
            "{} improvement over the baseline, model {}, {}; {}.", mname, model,
            heldout ? "tuned on all other tracks and scored on the column's track"
                    : "tuned and scored on the column's track",
            seeds_phrase(heldout ? in.held : in.own));
        row.push_back(w.figure(name, caption, [&](const fs::path& stem) {
          results::heatmap(stem, title, grid.columns, grid.mean_pct);
        }));
      }
      page.figures(row);
    }
  }
}

// (b) Figure 4: boxplots.
void write_boxplots(const ReportInput& in, ReportWriter& w, results::HtmlPage& page) {
  page.heading("Improvement per model (Figure 4)");
  std::vector<results::HtmlFigure> row;
  for (bool heldout : {false, true}) {
    std::map<std::string, std::map<std::string, std::vector<double>>> data;
    for (const auto& r : heldout ? in.held : in.own)
      for (ReportMetric metric : results::kReportMetrics)
        data[r.model][std::string(results::metric_name(metric))].push_back(results::improvement_pct(r, metric));
    if (data.empty()) continue;
    const std::string title = fmt::format("Improvement over the baseline [%] per model, all {}{} runs",
                                          heldout ? "held-out " : "", (heldout ? in.held : in.own).size());
    row.push_back(w.figure(heldout ? "boxplots_heldout" : "boxplots", title,
                           [&](const fs::path& stem) { results::boxplots(stem, title, data); }));
  }
  page.figures(row);
}

// (c) Table 1, one table per calibrator model and the UKF's table.
void write_rmse_tables(const ReportInput& in, ReportWriter& w, results::HtmlPage& page) {
  const std::vector<RunRecord>& runs = in.s.runs;
  const results::RmseTable t1 = results::rmse_table(runs_of(runs, in.ekf_models));
  if (!t1.rows.empty()) {
    const results::TextTable tt = results::text_table(t1);
    w.text("table1.csv", "report table", results::to_csv(t1));
    w.text("table1.md", "report table", results::to_markdown(tt));
    page.heading("Absolute RMSE per track and fitness mode (Table 1)");
    page.paragraph(
        fmt::format("Original = the baseline configuration; each model's column is the mean tuned RMSE over "
                    "seeds, the row's best in bold ({}). Also as table1.csv and table1.md.",
                    seeds_phrase(in.own)));
    page.table(tt);
  }
  // One table per calibrator model: each has its own baseline (its kind's
  // default settings), so they do not share an "original" column.
  for (const auto& model : in.calibrator_models) {
    const results::RmseTable tc = results::rmse_table(runs_of(runs, {model}));
    if (tc.rows.empty()) continue;
    const results::TextTable tt = results::text_table(tc);
    const std::string stem = "table1_" + file_safe(model);
    w.text(stem + ".csv", "report table", results::to_csv(tc));
    w.text(stem + ".md", "report table", results::to_markdown(tt));
    page.heading(fmt::format("Calibrated odometry RMSE per track, {}", model));
    page.paragraph(
        fmt::format("Dead-reckoning position RMSE of the odometry calibrated online by {}: original = the "
                    "paper's default settings, {} = the tuned settings ({}). Also as {}.csv and {}.md.",
                    model, model, seeds_phrase(runs_of(in.own, {model})), stem, stem));
    page.table(tt);
  }
  // The UKF's table: its own baseline (the default UKF noise).
  for (const auto& model : in.ukf_models) {
    const results::RmseTable tu = results::rmse_table(runs_of(runs, {model}));
    if (tu.rows.empty()) continue;
    const results::TextTable tt = results::text_table(tu);
    const std::string stem = "table1_" + file_safe(model);
    w.text(stem + ".csv", "report table", results::to_csv(tu));
    w.text(stem + ".md", "report table", results::to_markdown(tt));
    page.heading(fmt::format("Fused pose RMSE per track and fitness mode, {}", model));
    page.paragraph(
        fmt::format("Position RMSE of the pose integrated from the fusion UKF's (V, W): original = the default "
                    "UKF noise, {} = the tuned noise ({}). Also as {}.csv and {}.md.",
                    model, seeds_phrase(runs_of(in.own, {model})), stem, stem));
    page.table(tt);
  }
}

// (c) The generalisation table: tuned on the track vs held out.
void write_generalisation(const ReportInput& in, ReportWriter& w, results::HtmlPage& page,
                          std::vector<std::string>& notes) {
  page.heading("Generalisation: tuned on the track vs held out");
  std::string md;
  bool any = false;
  for (ReportMetric metric : results::kReportMetrics) {
    const auto rows = results::generalisation(in.s.runs, metric);
    if (rows.empty()) continue;
    any = true;
    const results::TextTable tt = results::text_table(rows, metric);
    md += results::to_markdown(tt) + "\n";
    page.table(tt);
  }
  if (any) {
    w.text("generalisation.md", "report table", md);
    page.paragraph("Per-track tuning overfits: the held-out column is what a configuration tuned on the "
                   "other tracks achieves on this one. Means over all modes and seeds.");
  } else {
    notes.emplace_back("no leave-one-track-out runs: set leave_one_out: true in the experiment for the "
                       "generalisation table and held-out heatmaps");
    page.paragraph("This experiment has no leave-one-track-out runs (leave_one_out: false).");
  }
}

// The fitness mode of the trajectories and convergence curves: the requested
// one, or the last mode with runs (with a note) when it has none. The store
// keeps modes as their numbers (results/run_record.h), read back here.
objectives::FitnessMode shown_mode(const ReportInput& in, std::vector<std::string>& notes) {
  const objectives::FitnessMode asked = in.req.mode;
  const std::vector<int> modes = results::report_modes(in.own);
  if (modes.empty() || std::find(modes.begin(), modes.end(), objectives::number(asked)) != modes.end())
    return asked;
  const std::optional<objectives::FitnessMode> last = objectives::fitness_mode_of_number(modes.back());
  if (!last)
    throw core::Failure(fmt::format("{}: mode {} of its runs is not a fitness mode, expected {}",
                                    in.req.store.string(), modes.back(), objectives::fitness_mode_choices()));
  notes.push_back(fmt::format("mode {} has no runs; trajectories and convergence use mode {}",
                              objectives::number(asked), objectives::number(*last)));
  return *last;
}

// One track's trajectory overlay: the reference (ground truth, or the
// position fixes when there is none), the baseline EKF and each EKF model's
// best run in `mode`.
results::HtmlFigure trajectory_figure(const ReportInput& in, ReportWriter& w, const std::string& name,
                                      const tracks::Track& track, objectives::FitnessMode mode) {
  const std::vector<RunRecord>& runs = in.s.runs;
  objectives::ReplayInput rin;
  try {
    rin = objectives::build_replay_input_any(track);
  } catch (const std::invalid_argument& ex) {
    throw core::Failure(ex.what());
  }
  std::vector<results::TrajectoryPath> paths;
  if (rin.reference_is_fixes) {
    // No ground truth: the fixes, and each filter's whole trajectory.
    results::TrajectoryPath fixes{"position fixes", {}, {}};
    for (const auto& p : rin.fixes) {
      fixes.xs_m.push_back(p.x());
      fixes.ys_m.push_back(p.y());
    }
    paths.push_back(std::move(fixes));
    paths.push_back(path_of("baseline EKF", objectives::ekf_trajectory(rin, objectives::baseline_noise())));
    for (const auto& model : in.ekf_models)
      if (const RunRecord* r = best_run(runs, model, name, mode))
        paths.push_back(path_of(fmt::format("{} tuned (mode {})", model, objectives::number(mode)),
                                objectives::ekf_trajectory(rin, run_noise(*r))));
    const std::string title = fmt::format("{}: position fixes, baseline and tuned EKF (mode {})", name,
                                          objectives::number(mode));
    return w.figure("trajectories_" + file_safe(name), title,
                    [&](const fs::path& stem) { results::trajectories(stem, title, paths); });
  }
  results::TrajectoryPath gt{"ground truth", {}, {}};
  for (const auto& p : rin.gt) {
    gt.xs_m.push_back(p.x());
    gt.ys_m.push_back(p.y());
  }
  paths.push_back(std::move(gt));
  const objectives::ReplayResult base = objectives::replay_ekf(rin, objectives::baseline_noise(), true);
  paths.push_back(path_of(fmt::format("baseline EKF (RMSE {:.1f} mm)", base.outcome.metrics.rmse_m * 1e3),
                          base.trajectory));
  for (const auto& model : in.ekf_models) {
    const RunRecord* r = best_run(runs, model, name, mode);
    if (!r) continue;
    const objectives::ReplayResult got = objectives::replay_ekf(rin, run_noise(*r), true);
    paths.push_back(path_of(fmt::format("{} tuned, seed {} (RMSE {:.1f} mm)", model, r->seed,
                                        got.outcome.metrics.rmse_m * 1e3),
                            got.trajectory));
  }
  const std::string title = fmt::format("{}: ground truth, baseline and tuned EKF (mode {})", name,
                                        objectives::number(mode));
  return w.figure("trajectories_" + file_safe(name), title,
                  [&](const fs::path& stem) { results::trajectories(stem, title, paths); });
}

// (d) Figure 5: trajectory overlays of the EKF models in `mode`.
void write_trajectories(const ReportInput& in, ReportWriter& w, results::HtmlPage& page,
                        std::vector<std::string>& notes, objectives::FitnessMode mode) {
  page.heading(fmt::format("Trajectories (Figure 5), fitness mode {}", objectives::number(mode)));
  if (!in.calibrator_models.empty())
    notes.push_back(
        fmt::format("trajectory overlays replay the EKF: the calibrator models ({}) are left out of them",
                    fmt::join(in.calibrator_models, ", ")));
  if (!in.ukf_models.empty())
    notes.push_back(
        fmt::format("trajectory overlays replay the EKF: the fusion UKF runs ({}) are left out of them",
                    fmt::join(in.ukf_models, ", ")));
  const auto track_data = in.ekf_models.empty() ? std::map<std::string, tracks::Track>{}
                                                : experiment_tracks(in.s.info, in.req.track_files);
  if (in.ekf_models.empty()) {
    page.paragraph("No EKF runs in this store: no trajectory overlays.");
    return;
  }
  std::vector<results::HtmlFigure> row;
  for (const auto& name : in.s.overlay_tracks) {
    const auto it = track_data.find(name);
    if (it == track_data.end()) {
      notes.push_back(fmt::format(
          "trajectory overlay of {} left out: its track file was not found (pass --track FILE)", name));
      continue;
    }
    row.push_back(trajectory_figure(in, w, name, it->second, mode));
  }
  if (!row.empty())
    page.paragraph("Each model's run with the lowest tuned RMSE on the track, replayed by the reference EKF.");
  page.figures(row);
}

// (e) Convergence curves: the EKF models' fitness (metres) and the
// calibrators' score (dimensionless) in separate figures.
void write_convergence(const ReportInput& in, ReportWriter& w, results::HtmlPage& page,
                       objectives::FitnessMode mode) {
  page.heading(fmt::format("Convergence, fitness mode {}", objectives::number(mode)));
  const auto is_calibrator = [&in](const std::string& model) {
    return std::find(in.calibrator_models.begin(), in.calibrator_models.end(), model) !=
           in.calibrator_models.end();
  };
  page.paragraph("Best fitness so far against evaluations: median over seeds as a line, min–max as a band.");
  for (bool calibrator : {false, true}) {
    std::vector<results::HtmlFigure> row;
    for (const auto& name : in.s.tracks) {
      std::map<std::string, std::vector<std::vector<results::ConvergencePoint>>> series;
      for (const auto& r : in.own)
        if (is_calibrator(r.model) == calibrator && r.track == name &&
            (calibrator || r.mode == objectives::number(mode)) && !r.convergence.empty())
          series[r.model].push_back(r.convergence);
      if (series.empty()) continue;
      const std::string title = calibrator ? fmt::format("{}: best calibration score vs evaluations", name)
                                           : fmt::format("{}: best fitness (mode {}) vs evaluations", name,
                                                         objectives::number(mode));
      const std::string stem = (calibrator ? "convergence_calibration_" : "convergence_") + file_safe(name);
      row.push_back(w.figure(stem, title, [&](const fs::path& p) { results::convergence(p, title, series); }));
    }
    if (calibrator && !row.empty())
      page.paragraph("Calibrator models: best calibration score (odotune/calibration/calibration_objective.h, "
                     "lower is better) against evaluations, whatever the fitness mode.");
    page.figures(row);
  }
}

}  // namespace

ReportOutcome write_report(const ReportRequest& req) {
  const CheckedStore s = open_checked(req);
  if (std::any_of(s.kinds.begin(), s.kinds.end(), [](const objectives::TunedModel& m) { return m.is_rl(); }))
    return write_rl_report(req, s.info, s.runs);  // rl-ekf and rl-ukf stand alone in an experiment

  const ReportInput in = split_runs(req, s);
  ReportOutcome out;
  out.experiment = s.info.name;
  out.runs = static_cast<long>(s.runs.size());
  out.heldout_runs = static_cast<long>(in.held.size());

  ReportWriter w(req.out_dir);
  results::HtmlPage page(fmt::format("odotune report: {}", s.info.name));
  write_intro(in, page);
  out.headline = headline(in);
  page.paragraph(out.headline + ".");
  write_heatmaps(in, w, page);
  write_boxplots(in, w, page);
  write_rmse_tables(in, w, page);
  write_generalisation(in, w, page, out.notes);
  const objectives::FitnessMode mode = shown_mode(in, out.notes);
  write_trajectories(in, w, page, out.notes, mode);
  write_convergence(in, w, page, mode);
  out.files = w.finish(page, out.notes);
  return out;
}

}  // namespace odotune::jobs
