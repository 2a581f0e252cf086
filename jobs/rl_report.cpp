// write_rl_report (jobs/rl_job.h): the report page of a store of rl-ekf runs.
#include <algorithm>
#include <limits>
#include <map>
#include <span>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "core/failure.h"
#include "jobs/report_writer.h"
#include "jobs/rl_job.h"
#include "results/figures.h"
#include "results/report_html.h"
#include "results/report_tables.h"

namespace odotune {
namespace {

namespace fs = std::filesystem;
using results::RunRecord;

std::string fitness_name(int mode) {
  const std::optional<RlFitness> f = rl_fitness_of_mode(mode);
  return f ? std::string(to_string(*f)) : fmt::format("mode {}", mode);
}

// Per bag and fitness, the run of lowest tuning fitness (its held-out scores
// play no part in the choice).
std::map<std::pair<std::string, int>, const RunRecord*> best_runs(const std::vector<RunRecord>& runs) {
  std::map<std::pair<std::string, int>, const RunRecord*> best;
  for (const RunRecord& r : runs) {
    const RunRecord*& b = best[{r.track, r.mode}];
    if (!b || r.best_fitness < b->best_fitness) b = &r;
  }
  return best;
}

results::TrajectoryPath path_of(std::string name, const std::vector<rlnode::TrajectoryPoint>& t) {
  results::TrajectoryPath p{std::move(name), {}, {}};
  for (const rlnode::TrajectoryPoint& q : t) {
    p.xs_m.push_back(q.state[filters::rl::kX]);
    p.ys_m.push_back(q.state[filters::rl::kY]);
  }
  return p;
}

// The outage protocol's trajectories of each bag's best runs, replayed from the bag.
void trajectory_figures(const Experiment& e, const std::vector<RunRecord>& runs, ReportWriter& w,
                        results::HtmlPage& page, ReportOutcome& out) {
  const ExperimentRl& x = *e.robot_localization;
  const auto best = best_runs(runs);
  std::vector<results::HtmlFigure> row;
  for (const std::string& bag : e.tracks) {
    const std::string name = fs::path(bag).stem().string();
    if (!fs::exists(bag)) {
      out.notes.push_back(fmt::format("trajectories of {} left out: {} was not found", name, bag));
      continue;
    }
    const RlLoaded loaded = load_rl(rl_source_of(x, bag));
    const rlnode::Recording& rec = loaded.rec;
    const std::int64_t from = rec.start_ns + static_cast<std::int64_t>(std::llround(x.until_s * 1e9));
    const std::int64_t end = x.end_s ? rec.start_ns + static_cast<std::int64_t>(std::llround(*x.end_s * 1e9))
                                     : std::numeric_limits<std::int64_t>::max();
    const rlnode::ReplaySettings base = rlnode::settings_of(rec.params);
    const rlnode::ReplayOutput b = outage_run(rec, base, from, end, true);
    std::vector<results::TrajectoryPath> paths;
    results::TrajectoryPath held{"held-out GPS fixes", {}, {}};
    for (const rlnode::ScoredFix& f : b.scored) {
      held.xs_m.push_back(f.measured.x());
      held.ys_m.push_back(f.measured.y());
    }
    paths.push_back(std::move(held));
    paths.push_back(path_of(fmt::format("the file's values ({:.2f} m)", score_of(std::span(&b, 1)).rmse_m),
                            b.trajectory));
    for (const auto& [key, r] : best) {
      if (key.first != name) continue;
      rlnode::ReplaySettings s = base;
      std::string why;
      if (!apply_rl_factors(rec.params, r->param_names, r->params, &s, &why))
        throw Failure(fmt::format("run {}: {}", results::run_key(*r), why));
      const rlnode::ReplayOutput t = outage_run(rec, s, from, end, true);
      paths.push_back(path_of(fmt::format("tuned, {} seed {} ({:.2f} m)", fitness_name(r->mode), r->seed,
                                          score_of(std::span(&t, 1)).rmse_m),
                              t.trajectory));
    }
    const std::string title = fmt::format(
        "{}: GPS fused until {} s only; robot_localization's EKF, the file's and tuned values", name,
        x.until_s);
    row.push_back(w.figure("trajectories_" + file_safe(name), title,
                           [&](const fs::path& stem) { results::trajectories(stem, title, paths); }));
  }
  if (!row.empty())
    page.paragraph("Per bag and fitness, the run of lowest tuning fitness, replayed from the bag under the "
                   "GPS-outage protocol; the RMSE at the held-out fixes in brackets.");
  page.figures(row);
}

}  // namespace

ReportOutcome write_rl_report(const ReportRequest& req, const results::ExperimentInfo& info,
                              const std::vector<RunRecord>& runs) {
  const Experiment e = parse_experiment(info.text, info.file);
  if (!e.robot_localization) throw Failure(fmt::format("{}: not an rl-ekf experiment", req.store.string()));
  const ExperimentRl& x = *e.robot_localization;
  ReportOutcome out;
  out.experiment = info.name;
  out.runs = static_cast<long>(runs.size());
  ReportWriter w(req.out_dir);
  results::HtmlPage page(fmt::format("odotune report: {}", info.name));
  page.paragraph(fmt::format(
      "Experiment **{}** (file hash {}, odotune {}): {} runs of robot_localization's EKF (model rl-ekf) with "
      "the parameter file {}, on {}. Each run tunes the file's process noise on a bag before {} s and is "
      "scored after it{}, on data the tune never saw: GPS fused until {} s and none after, the error of the "
      "filter at every later fix (RMSE, MAE, MAXE). The baseline is the file's own values. Improvement % = "
      "100 · (baseline − tuned) / baseline, positive is better.",
      info.name, info.hash, info.code_version, runs.size(), x.params.string(),
      fmt::join(results::report_tracks(runs), ", "), x.until_s,
      x.end_s ? fmt::format(" until {} s", *x.end_s) : "", x.until_s));
  std::map<int, std::vector<double>> by_mode;
  for (const RunRecord& r : runs) by_mode[r.mode].push_back(r.improvement_rmse_pct());
  std::vector<std::string> parts;
  for (const auto& [mode, v] : by_mode) {
    double sum = 0.0;
    for (double p : v) sum += p;
    parts.push_back(fmt::format("{} {:+.1f} %", fitness_name(mode), sum / static_cast<double>(v.size())));
  }
  out.headline = fmt::format("mean held-out GPS-outage RMSE improvement per fitness: {}",
                             fmt::join(parts, ", "));
  page.paragraph(out.headline + ".");

  const results::RmseTable t = results::rmse_table(runs, results::report_modes(runs));
  const results::TextTable tt = results::text_table(t);
  w.text("table_rl.csv", "report table", results::to_csv(t));
  w.text("table_rl.md", "report table", results::to_markdown(tt));
  page.heading("Held-out GPS-outage RMSE per bag and fitness");
  page.paragraph(fmt::format("Original = the file's own values; rl-ekf = the tuned values ({}); the lower "
                             "(better) of the two in bold. Modes: 8 heldout-fixes, 10 outage, 11 both. Also as "
                             "table_rl.csv and table_rl.md.",
                             seeds_phrase(runs)));
  page.table(tt);

  page.heading("Improvement per fitness");
  std::map<std::string, std::map<std::string, std::vector<double>>> data;
  for (const RunRecord& r : runs)
    for (results::ReportMetric metric : results::kReportMetrics)
      data[fitness_name(r.mode)][std::string(results::metric_name(metric))].push_back(
          results::improvement_pct(r, metric));
  const std::string box_title = fmt::format("Held-out improvement [%] per fitness, all {} runs", runs.size());
  page.figures({w.figure("boxplots", box_title,
                         [&](const fs::path& stem) { results::boxplots(stem, box_title, data); })});

  page.heading("Trajectories");
  trajectory_figures(e, runs, w, page, out);

  page.heading("Convergence");
  page.paragraph("Best tuning fitness so far against evaluations: median over seeds as a line, min–max as a "
                 "band (outage and heldout-fixes in metres; both is dimensionless).");
  std::vector<results::HtmlFigure> row;
  for (const std::string& bag : results::report_tracks(runs)) {
    std::map<std::string, std::vector<std::vector<results::ConvergencePoint>>> series;
    for (const RunRecord& r : runs)
      if (r.track == bag && !r.convergence.empty()) series[fitness_name(r.mode)].push_back(r.convergence);
    if (series.empty()) continue;
    const std::string title = fmt::format("{}: best tuning fitness vs evaluations", bag);
    row.push_back(w.figure("convergence_" + file_safe(bag), title,
                           [&](const fs::path& p) { results::convergence(p, title, series); }));
  }
  page.figures(row);

  out.files = w.finish(page, out.notes);
  return out;
}

}  // namespace odotune
