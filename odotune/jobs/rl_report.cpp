// write_rl_report (odotune/jobs/rl_job.h): the report page of a store of rl-ekf or
// rl-ukf runs.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <span>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <odotune/core/failure.h>
#include <odotune/jobs/report_writer.h>
#include <odotune/jobs/rl_job.h>
#include <odotune/results/figures.h>
#include <odotune/results/param_range_figure.h>
#include <odotune/results/report_html.h>
#include <odotune/results/report_tables.h>

namespace odotune::jobs {
namespace {

namespace fs = std::filesystem;
using results::RunRecord;

std::string fitness_name(int mode) {
  const std::optional<objectives::RlFitness> f = objectives::rl_fitness_of_mode(mode);
  return f ? std::string(objectives::to_string(*f)) : fmt::format("mode {}", mode);
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

results::TrajectoryPath report_path_of(std::string name, const std::vector<rlnode::TrajectoryPoint>& t) {
  results::TrajectoryPath p{std::move(name), {}, {}};
  for (const rlnode::TrajectoryPoint& q : t) {
    p.xs_m.push_back(q.state[filters::rl::kX]);
    p.ys_m.push_back(q.state[filters::rl::kY]);
  }
  return p;
}

// "EKF" or "UKF": the filter of the experiment's model.
std::string_view filter_label(const formats::Experiment& e) {
  return filters::rl::display_name(e.models.front().rl_filter());
}

// The outage protocol's trajectories of each bag's best runs, replayed from the bag.
void trajectory_figures(const formats::Experiment& e, const std::vector<RunRecord>& runs, ReportWriter& w,
                        results::HtmlPage& page, ReportOutcome& out) {
  const formats::ExperimentRl& x = *e.robot_localization;
  const auto best = best_runs(runs);
  std::vector<results::HtmlFigure> row;
  for (const std::string& bag : e.tracks) {
    const std::string name = fs::path(bag).stem().string();
    if (!fs::exists(bag)) {
      out.notes.push_back(fmt::format("trajectories of {} left out: {} was not found", name, bag));
      continue;
    }
    const RlLoaded loaded = load_rl(rl_source_of(x, bag, e.models.front().rl_filter()));
    const rlnode::Recording& rec = loaded.rec;
    const std::int64_t from = rl_time_ns(rec, x.until_s);
    const std::int64_t end = x.end_s ? rl_time_ns(rec, *x.end_s) : std::numeric_limits<std::int64_t>::max();
    const rlnode::ReplaySettings base = rlnode::settings_of(rec.params);
    const rlnode::ReplayOutput b = objectives::outage_run(rec, base, from, end, true);
    std::vector<results::TrajectoryPath> paths;
    results::TrajectoryPath held{"held-out GPS fixes", {}, {}};
    for (const rlnode::ScoredFix& f : b.scored) {
      held.xs_m.push_back(f.measured.x());
      held.ys_m.push_back(f.measured.y());
    }
    paths.push_back(std::move(held));
    paths.push_back(report_path_of(fmt::format("the file's values ({})",
                                               rmse_text(2, objectives::score_of(std::span(&b, 1)).rmse_m)),
                                   b.trajectory));
    for (const auto& [key, r] : best) {
      if (key.first != name) continue;
      rlnode::ReplaySettings s = base;
      std::string why;
      if (!objectives::apply_rl_factors(rec.params, r->param_names, r->params, &s, &why))
        throw core::Failure(fmt::format("run {}: {}", results::run_key(*r), why));
      const rlnode::ReplayOutput t = objectives::outage_run(rec, s, from, end, true);
      paths.push_back(report_path_of(fmt::format("tuned, {} seed {} ({})", fitness_name(r->mode), r->seed,
                                                 rmse_text(2, objectives::score_of(std::span(&t, 1)).rmse_m)),
                                     t.trajectory));
    }
    const std::string title = fmt::format(
        "{}: GPS fused until {} s only; robot_localization's {}, the file's and tuned values", name, x.until_s,
        filter_label(e));
    row.push_back(w.figure("trajectories_" + file_safe(name), title,
                           [&](const fs::path& stem) { results::trajectories(stem, title, paths); }));
  }
  if (!row.empty())
    page.paragraph("Per bag and fitness, the run of lowest tuning fitness, replayed from the bag under the "
                   "GPS-outage protocol; the RMSE at the held-out fixes in brackets.");
  page.figures(row);
}

// The seeds of the runs, ascending.
std::vector<std::uint64_t> seeds_of(const std::vector<RunRecord>& runs) {
  std::vector<std::uint64_t> seeds;
  for (const RunRecord& r : runs)
    if (std::find(seeds.begin(), seeds.end(), r.seed) == seeds.end()) seeds.push_back(r.seed);
  std::sort(seeds.begin(), seeds.end());
  return seeds;
}

// Per bag and fitness: the held-out improvement and tuned RMSE over seeds.
void seed_spread_section(const std::vector<RunRecord>& runs, ReportWriter& w, results::HtmlPage& page) {
  page.heading("Spread over seeds");
  const std::vector<results::SeedSpreadRow> rows = results::seed_spread(runs, runs.front().model);
  const bool several = std::any_of(rows.begin(), rows.end(), [](const auto& r) { return r.runs > 1; });
  if (!several) {
    page.paragraph("One seed per bag and fitness: no spread over seeds to show (list more seeds in the "
                   "experiment to see how much the tune depends on its seed).");
    return;
  }
  const results::TextTable t = results::text_table(rows, [](int mode) { return fitness_name(mode); });
  w.text("table_rl_seeds.md", "report table", results::to_markdown(t));
  page.paragraph(fmt::format("Per bag and fitness, over its runs' seeds ({}): the held-out GPS-outage RMSE "
                             "improvement and the tuned RMSE as min / median / max. Also as table_rl_seeds.md.",
                             fmt::join(seeds_of(runs), ", ")));
  page.table(t);
}

// A run whose ranges can be shown: one per parameter.
bool has_ranges(const RunRecord& r) {
  return !r.param_ranges.empty() && r.param_ranges.size() == r.param_names.size();
}

// One bag and fitness (`cell`: its runs by seed): a row per parameter appended
// to `t`, a cell per seed, and the figure's series, one per seed with ranges.
std::vector<results::ParamRangeSeries> range_rows(const std::vector<const RunRecord*>& cell,
                                                  const std::vector<std::uint64_t>& seeds,
                                                  const std::vector<std::string>& params,
                                                  const std::string& bag, int mode, results::TextTable& t) {
  std::vector<results::ParamRangeSeries> series;
  for (const RunRecord* r : cell)
    if (has_ranges(*r)) series.push_back({fmt::format("seed {}", r->seed), {}, {}});
  for (const std::string& name : params) {
    std::vector<std::string> cells = {bag, fitness_name(mode), name};
    std::size_t k = 0;
    for (std::uint64_t s : seeds) {
      const auto it = std::find_if(cell.begin(), cell.end(), [s](const RunRecord* r) { return r->seed == s; });
      if (it == cell.end()) {
        cells.push_back("–");
        continue;
      }
      const RunRecord& r = **it;
      const auto at = std::find(r.param_names.begin(), r.param_names.end(), name);
      if (at == r.param_names.end()) {
        cells.push_back("–");
        if (has_ranges(r)) {
          series[k].values.push_back(std::numeric_limits<double>::quiet_NaN());
          series[k].ranges.push_back({std::numeric_limits<double>::quiet_NaN(),
                                      std::numeric_limits<double>::quiet_NaN(), true});
          ++k;
        }
        continue;
      }
      const auto i = static_cast<std::size_t>(at - r.param_names.begin());
      const double value = i < r.params.size() ? r.params[i] : std::numeric_limits<double>::quiet_NaN();
      if (!has_ranges(r)) {
        cells.push_back(fmt::format("{:.3g}, no range stored", value));
        continue;
      }
      cells.push_back(results::param_range_text(value, r.param_ranges[i]));
      series[k].values.push_back(value);
      series[k].ranges.push_back(r.param_ranges[i]);
      ++k;
    }
    t.rows.push_back(std::move(cells));
  }
  return series;
}

// "What the recording determined": per bag × fitness, each parameter's tuned
// factor and range for every seed, as a table and a figure.
void determined_section(const std::vector<RunRecord>& runs, ReportWriter& w, results::HtmlPage& page) {
  page.heading("What the recording determined");
  const bool any = std::any_of(runs.begin(), runs.end(), has_ranges);
  if (!any) {
    page.paragraph("No parameter ranges are stored for these runs (their tune did not profile its parameters, "
                   "or they were stored before odotune kept ranges), so this section has nothing to show.");
    return;
  }
  page.paragraph(
      "Each tuned parameter is a factor on the file's value (1 = the file's own). Its range is where the tuning "
      "fitness stays within 2 % of its best: a narrow range means the recording pins the parameter; a parameter "
      "whose range holds the file's value and which the run therefore kept is not determined by this "
      "recording. Per bag and fitness, a figure draws the ranges on a log axis, one bar per seed, the tuned "
      "factor as a dot and the file's value as a dashed line, and a table gives the numbers. Also as "
      "table_rl_ranges.md.");
  const std::vector<std::uint64_t> seeds = seeds_of(runs);
  results::TextTable t;  // every bag and fitness, for table_rl_ranges.md
  t.header = {"Track", "Fitness", "Parameter"};
  for (std::uint64_t s : seeds) t.header.push_back(fmt::format("seed {}", s));
  t.numeric.assign(t.header.size(), false);
  for (const std::string& bag : results::report_tracks(runs))
    for (int mode : results::report_modes(runs)) {
      std::vector<const RunRecord*> cell;  // by seed, ascending
      for (std::uint64_t s : seeds)
        for (const RunRecord& r : runs)
          if (r.track == bag && r.mode == mode && r.seed == s) cell.push_back(&r);
      if (cell.empty()) continue;
      std::vector<std::string> params;  // in the order of the first run that names them
      for (const RunRecord* r : cell)
        for (const std::string& n : r->param_names)
          if (std::find(params.begin(), params.end(), n) == params.end()) params.push_back(n);
      const std::size_t first_row = t.rows.size();
      const std::vector<results::ParamRangeSeries> series = range_rows(cell, seeds, params, bag, mode, t);
      // On the page: the figure, then this bag and fitness's rows without their first two columns.
      if (!series.empty()) {
        const std::string title = fmt::format("{}, fitness {}: tuned factors and their ranges", bag,
                                              fitness_name(mode));
        page.figures(
            {w.figure(fmt::format("ranges_{}_{}", file_safe(bag), mode), title, [&](const fs::path& stem) {
              results::param_ranges_figure(stem, title, "factor on the file's value (log scale)", params,
                                           series, 1.0, "the file's value (factor 1)");
            })});
      }
      results::TextTable part;
      part.header.assign(t.header.begin() + 2, t.header.end());
      part.numeric.assign(part.header.size(), false);
      for (std::size_t i = first_row; i < t.rows.size(); ++i)
        part.rows.emplace_back(t.rows[i].begin() + 2, t.rows[i].end());
      page.paragraph(fmt::format("**{}, fitness {}**: per parameter and seed, the tuned factor [its range].",
                                 bag, fitness_name(mode)));
      page.table(part);
    }
  w.text("table_rl_ranges.md", "report table", results::to_markdown(t));
}

}  // namespace

ReportOutcome write_rl_report(const ReportRequest& req, const results::ExperimentInfo& info,
                              const std::vector<RunRecord>& runs) {
  const formats::Experiment e = formats::parse_experiment(info.text, info.file);
  if (!e.robot_localization)
    throw core::Failure(fmt::format("{}: not an rl-ekf or rl-ukf experiment", req.store.string()));
  const std::string model = objectives::to_string(e.models.front());
  const formats::ExperimentRl& x = *e.robot_localization;
  ReportOutcome out;
  out.experiment = info.name;
  out.runs = static_cast<long>(runs.size());
  ReportWriter w(req.out_dir);
  results::HtmlPage page(fmt::format("odotune report: {}", info.name));
  const std::vector<std::uint64_t> seeds = seeds_of(runs);
  page.paragraph(fmt::format(
      "Experiment **{}** (file hash {}, odotune {}): {} runs of robot_localization's {} (model {}) with "
      "the parameter file {}, on {}, {} {} ({}). Each run tunes the file's process noise on a bag before {} s "
      "and is scored after it{}, on data the tune never saw: GPS fused until {} s and none after, the error of "
      "the filter at every later fix (RMSE, MAE, MAXE). The baseline is the file's own values. Improvement % = "
      "100 · (baseline − tuned) / baseline, positive is better.",
      info.name, info.hash, info.code_version, runs.size(), filter_label(e), model, x.params.string(),
      fmt::join(results::report_tracks(runs), ", "), seeds.size(), seeds.size() == 1 ? "seed" : "seeds",
      fmt::join(seeds, ", "), x.until_s, x.end_s ? fmt::format(" until {} s", *x.end_s) : "", x.until_s));
  std::map<int, std::vector<double>> by_mode;
  for (const RunRecord& r : runs) by_mode[r.mode].push_back(r.improvement_rmse_pct());
  std::vector<std::string> parts;
  for (const auto& [mode, v] : by_mode) {
    double sum = 0.0;
    long finite = 0;
    for (double p : v) {
      if (!std::isfinite(p)) continue;
      sum += p;
      ++finite;
    }
    const long diverged = static_cast<long>(v.size()) - finite;
    const std::string mean = finite > 0 ? fmt::format("{:+.1f} %", sum / static_cast<double>(finite)) : "n/a";
    parts.push_back(fmt::format("{} {}{}", fitness_name(mode), mean,
                                diverged > 0 ? fmt::format(" ({} of {} runs diverged)", diverged, v.size())
                                             : ""));
  }
  out.headline = fmt::format("mean held-out GPS-outage RMSE improvement per fitness: {}",
                             fmt::join(parts, ", "));
  page.paragraph(out.headline + ".");

  const results::RmseTable t = results::rmse_table(runs, results::report_modes(runs));
  const results::TextTable tt = results::text_table(t);
  w.text("table_rl.csv", "report table", results::to_csv(t));
  w.text("table_rl.md", "report table", results::to_markdown(tt));
  page.heading("Held-out GPS-outage RMSE per bag and fitness");
  page.paragraph(fmt::format("Original = the file's own values; {} = the tuned values ({}); the lower "
                             "(better) of the two in bold. Modes: 8 heldout-fixes, 10 outage, 11 both. Also as "
                             "table_rl.csv and table_rl.md.",
                             model, seeds_phrase(runs)));
  page.table(tt);

  seed_spread_section(runs, w, page);

  page.heading("Improvement per fitness");
  std::map<std::string, std::map<std::string, std::vector<double>>> data;
  for (const RunRecord& r : runs)
    for (results::ReportMetric metric : results::kReportMetrics)
      data[fitness_name(r.mode)][std::string(results::metric_name(metric))].push_back(
          results::improvement_pct(r, metric));
  const std::string box_title = fmt::format("Held-out improvement [%] per fitness, all {} runs", runs.size());
  const std::string box_caption =
      box_title + "; one point per run (seed), over a box of the quartiles for 4 runs or more, else over the "
                  "runs' range with a line at their median";
  page.figures({w.figure("boxplots", box_caption, [&](const fs::path& stem) {
    results::boxplots(stem, box_title, data, {"fitness", true});
  })});

  determined_section(runs, w, page);

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

}  // namespace odotune::jobs
