// The report's numbers, computed from a store's runs (plain data in, plain
// data out; the figures and the HTML page are drawn from these):
//  - improvement grids: improvement % over the baseline per fitness mode ×
//    track, mean over seeds, per model and metric (the study's Figure 3),
//    for per-track runs and for leave-one-track-out runs;
//  - Table 1: absolute RMSE per track × mode, original (baseline) vs each
//    model (mean over seeds), as CSV and Markdown;
//  - generalisation: per model × track, the per-track improvement next to
//    the held-out one (tuned on the other tracks, scored on this one).
// Improvement % = 100·(baseline − tuned)/baseline (positive = better).
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include <odotune/objectives/fitness_mode.h>
#include <odotune/results/run_record.h>

namespace odotune::results {

enum class ReportMetric { rmse, mae, maxe };
inline constexpr ReportMetric kReportMetrics[] = {ReportMetric::rmse, ReportMetric::mae, ReportMetric::maxe};
std::string_view metric_name(ReportMetric m);  // "RMSE", "MAE", "MAXE"
double improvement_pct(const RunRecord& r, ReportMetric m);

// Models present, in the order rq, alpha, gyro, then any other by name.
std::vector<std::string> report_models(const std::vector<RunRecord>& runs);
// Tracks scored by any run, in the order first stored.
std::vector<std::string> report_tracks(const std::vector<RunRecord>& runs);
// Stored fitness mode numbers present, ascending.
std::vector<int> report_modes(const std::vector<RunRecord>& runs);

struct ImprovementGrid {
  std::vector<std::string> columns;           // tracks
  std::vector<std::vector<double>> mean_pct;  // 7 rows (modes 1..7) × columns; NaN = no run
  std::vector<std::vector<int>> runs;         // how many runs each mean is over
  bool empty() const;                         // no run at all
};
// Runs of `model` that are (heldout) or are not (!heldout) leave-one-out
// runs, grouped by mode and scored track; columns are `tracks`.
ImprovementGrid improvement_grid(const std::vector<RunRecord>& runs, const std::string& model,
                                 ReportMetric metric, bool heldout, const std::vector<std::string>& tracks);

struct RmseTable {
  std::vector<std::string> models;
  struct Row {
    std::string track;
    int mode = 0;
    double original_m = 0.0;      // baseline RMSE (mean over the row's runs)
    std::vector<double> tuned_m;  // per model: mean tuned RMSE over seeds; NaN = no run
  };
  std::vector<Row> rows;  // tracks in report order, modes ascending
};
// From per-track runs only (leave-one-out runs are in the generalisation table).
// Rows for `modes` only (default: the paper's modes 1..7), in that order.
RmseTable rmse_table(const std::vector<RunRecord>& runs,
                     const std::vector<int>& modes = objectives::ground_truth_mode_numbers());
// RMSE in mm with 2 decimals; header "track,mode,original_mm,<model>_mm…";
// a missing value is an empty field.
std::string to_csv(const RmseTable& t);

// A table as text cells, for Markdown and HTML alike. A cell written
// "**x**" is emphasised.
struct TextTable {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::vector<bool> numeric;  // per column: right-aligned
};
// Table 1 in mm, the best (lowest) value of each row emphasised: the
// original's when no tuned value is lower, every value equal to it on a tie.
TextTable text_table(const RmseTable& t);
// GitHub-flavoured Markdown.
std::string to_markdown(const TextTable& t);

// The spread over seeds of `model`'s per-track runs, per track × mode
// (tracks in report order, modes ascending): how many runs (seeds), and the
// RMSE improvement % and the tuned RMSE as min / median / max over them.
struct SeedSpreadRow {
  std::string track;
  int mode = 0;
  int runs = 0;
  double improvement_min_pct = 0.0, improvement_median_pct = 0.0, improvement_max_pct = 0.0;
  double tuned_min_m = 0.0, tuned_median_m = 0.0, tuned_max_m = 0.0;
};
std::vector<SeedSpreadRow> seed_spread(const std::vector<RunRecord>& runs, const std::string& model);
// Track, Mode (`mode_label(mode)`, or the number when empty), Seeds, the
// improvement's min / median / max in % and the tuned RMSE's in mm.
TextTable text_table(const std::vector<SeedSpreadRow>& rows,
                     const std::function<std::string(int)>& mode_label = {});

// A tuned factor with its range, for a table cell: "1.84 [0.912, 3.2]", or
// "1, not determined by this recording [0.01, 100]" (3 significant digits).
std::string param_range_text(double value, const ParamRange& range);

struct GeneralisationRow {
  std::string model, track;
  double per_track_pct = 0.0;  // mean improvement over modes and seeds, tuned on this track
  double heldout_pct = 0.0;    // the same, tuned on all other tracks
  int per_track_runs = 0, heldout_runs = 0;
};
// One row per model × track that has both kinds of runs.
std::vector<GeneralisationRow> generalisation(const std::vector<RunRecord>& runs, ReportMetric metric);
TextTable text_table(const std::vector<GeneralisationRow>& rows, ReportMetric metric);

}  // namespace odotune::results
