#include <odotune/results/report_tables.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include <fmt/format.h>

#include <odotune/core/robust_stats.h>

namespace odotune::results {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t kModes = objectives::kGroundTruthModes.size();

// The grid row of a stored mode number: modes against ground truth only.
std::optional<std::size_t> grid_row(int stored_mode) {
  const std::optional<objectives::FitnessMode> m = objectives::fitness_mode_of_number(stored_mode);
  if (!m || objectives::is_fix_cv(*m)) return std::nullopt;
  return static_cast<std::size_t>(objectives::number(*m) - 1);
}

struct Mean {
  double sum = 0.0;
  int n = 0;
  void add(double v) {
    sum += v;
    ++n;
  }
  double value() const { return n ? sum / n : kNaN; }
};

std::string mm(double v_m) { return std::isfinite(v_m) ? fmt::format("{:.2f}", v_m * 1e3) : ""; }
std::string pct(double v) { return std::isfinite(v) ? fmt::format("{:+.1f} %", v) : "n/a"; }
}  // namespace

std::string_view metric_name(ReportMetric m) {
  switch (m) {
    case ReportMetric::rmse: return "RMSE";
    case ReportMetric::mae: return "MAE";
    case ReportMetric::maxe: return "MAXE";
  }
  return "?";
}

double improvement_pct(const RunRecord& r, ReportMetric m) {
  switch (m) {
    case ReportMetric::rmse: return r.improvement_rmse_pct();
    case ReportMetric::mae: return r.improvement_mae_pct();
    case ReportMetric::maxe: return r.improvement_maxe_pct();
  }
  return kNaN;
}

std::vector<std::string> report_models(const std::vector<RunRecord>& runs) {
  static const std::vector<std::string> known = {"rq", "alpha", "gyro"};
  std::vector<std::string> out, others;
  for (const auto& k : known)
    if (std::any_of(runs.begin(), runs.end(), [&](const RunRecord& r) { return r.model == k; }))
      out.push_back(k);
  for (const auto& r : runs)
    if (std::find(known.begin(), known.end(), r.model) == known.end() &&
        std::find(others.begin(), others.end(), r.model) == others.end())
      others.push_back(r.model);
  std::sort(others.begin(), others.end());
  out.insert(out.end(), others.begin(), others.end());
  return out;
}

std::vector<std::string> report_tracks(const std::vector<RunRecord>& runs) {
  std::vector<std::string> out;
  for (const auto& r : runs)
    if (std::find(out.begin(), out.end(), r.scored_track()) == out.end()) out.push_back(r.scored_track());
  return out;
}

std::vector<int> report_modes(const std::vector<RunRecord>& runs) {
  std::vector<int> out;
  for (const auto& r : runs)
    if (std::find(out.begin(), out.end(), r.mode) == out.end()) out.push_back(r.mode);
  std::sort(out.begin(), out.end());
  return out;
}

bool ImprovementGrid::empty() const {
  for (const auto& row : runs)
    for (int n : row)
      if (n) return false;
  return true;
}

ImprovementGrid improvement_grid(const std::vector<RunRecord>& runs, const std::string& model,
                                 ReportMetric metric, bool heldout, const std::vector<std::string>& tracks) {
  std::vector<std::vector<Mean>> acc(kModes, std::vector<Mean>(tracks.size()));
  for (const auto& r : runs) {
    const std::optional<std::size_t> row = grid_row(r.mode);
    if (r.model != model || r.is_heldout() != heldout || !row) continue;
    const auto it = std::find(tracks.begin(), tracks.end(), r.scored_track());
    if (it == tracks.end()) continue;
    acc[*row][static_cast<std::size_t>(it - tracks.begin())].add(improvement_pct(r, metric));
  }
  ImprovementGrid g;
  g.columns = tracks;
  for (const auto& row : acc) {
    g.mean_pct.emplace_back();
    g.runs.emplace_back();
    for (const auto& m : row) {
      g.mean_pct.back().push_back(m.value());
      g.runs.back().push_back(m.n);
    }
  }
  return g;
}

RmseTable rmse_table(const std::vector<RunRecord>& runs, const std::vector<int>& modes) {
  RmseTable t;
  t.models = report_models(runs);
  // (track, mode) → original mean, per-model tuned means.
  std::map<std::pair<std::string, int>, std::pair<Mean, std::vector<Mean>>> acc;
  for (const auto& r : runs) {
    if (r.is_heldout()) continue;
    auto& cell = acc[{r.track, r.mode}];
    cell.second.resize(t.models.size());
    cell.first.add(r.baseline.rmse_m);
    const auto m = std::find(t.models.begin(), t.models.end(), r.model) - t.models.begin();
    cell.second[static_cast<std::size_t>(m)].add(r.tuned.rmse_m);
  }
  for (const auto& track : report_tracks(runs))
    for (int mode : modes) {
      const auto it = acc.find({track, mode});
      if (it == acc.end()) continue;
      RmseTable::Row row{track, mode, it->second.first.value(), {}};
      for (const auto& m : it->second.second) row.tuned_m.push_back(m.value());
      t.rows.push_back(std::move(row));
    }
  return t;
}

std::string to_csv(const RmseTable& t) {
  std::string s = "track,mode,original_mm";
  for (const auto& m : t.models) s += "," + m + "_mm";
  s += "\n";
  for (const auto& r : t.rows) {
    s += fmt::format("{},{},{}", r.track, r.mode, mm(r.original_m));
    for (double v : r.tuned_m) s += "," + mm(v);
    s += "\n";
  }
  return s;
}

TextTable text_table(const RmseTable& t) {
  TextTable out;
  out.header = {"Track", "Mode", "Original [mm]"};
  for (const auto& m : t.models) out.header.push_back(m + " [mm]");
  out.numeric.assign(out.header.size(), true);
  out.numeric[0] = false;
  for (const auto& r : t.rows) {
    // Lower error is better: the row's lowest value, the original included,
    // is the best (a tuned value worse than the original is never marked).
    double best = std::isfinite(r.original_m) ? r.original_m : std::numeric_limits<double>::infinity();
    for (double v : r.tuned_m)
      if (std::isfinite(v)) best = std::min(best, v);
    const auto cell = [best](double v) {
      return !std::isfinite(v) ? std::string("–") : v == best ? "**" + mm(v) + "**" : mm(v);
    };
    std::vector<std::string> cells = {r.track, std::to_string(r.mode),
                                      std::isfinite(r.original_m) ? cell(r.original_m) : mm(r.original_m)};
    for (double v : r.tuned_m) cells.push_back(cell(v));
    out.rows.push_back(std::move(cells));
  }
  return out;
}

std::string to_markdown(const TextTable& t) {
  std::string s = "|";
  for (const auto& h : t.header) s += " " + h + " |";
  s += "\n|";
  for (std::size_t i = 0; i < t.header.size(); ++i)
    s += (i < t.numeric.size() && t.numeric[i]) ? "---:|" : "---|";
  s += "\n";
  for (const auto& row : t.rows) {
    s += "|";
    for (const auto& c : row) s += " " + c + " |";
    s += "\n";
  }
  return s;
}

namespace {
double median_of(std::vector<double> v) { return core::median(std::move(v)); }
}  // namespace

std::vector<SeedSpreadRow> seed_spread(const std::vector<RunRecord>& runs, const std::string& model) {
  std::map<std::pair<std::string, int>, std::pair<std::vector<double>, std::vector<double>>> acc;
  for (const auto& r : runs)
    if (r.model == model && !r.is_heldout()) {
      auto& cell = acc[{r.track, r.mode}];
      cell.first.push_back(r.improvement_rmse_pct());
      cell.second.push_back(r.tuned.rmse_m);
    }
  std::vector<SeedSpreadRow> out;
  for (const auto& track : report_tracks(runs))
    for (int mode : report_modes(runs)) {
      const auto it = acc.find({track, mode});
      if (it == acc.end()) continue;
      const auto& [pct_v, tuned_v] = it->second;
      const auto [pmin, pmax] = std::minmax_element(pct_v.begin(), pct_v.end());
      const auto [tmin, tmax] = std::minmax_element(tuned_v.begin(), tuned_v.end());
      out.push_back({track, mode, static_cast<int>(pct_v.size()), *pmin, median_of(pct_v), *pmax, *tmin,
                     median_of(tuned_v), *tmax});
    }
  return out;
}

TextTable text_table(const std::vector<SeedSpreadRow>& rows,
                     const std::function<std::string(int)>& mode_label) {
  TextTable t;
  t.header = {"Track",       "Mode",    "Seeds", "RMSE improvement min", "median", "max", "Tuned RMSE min [mm]",
              "median [mm]", "max [mm]"};
  t.numeric = {false, false, true, true, true, true, true, true, true};
  for (const auto& r : rows)
    t.rows.push_back({r.track, mode_label ? mode_label(r.mode) : std::to_string(r.mode), std::to_string(r.runs),
                      pct(r.improvement_min_pct), pct(r.improvement_median_pct), pct(r.improvement_max_pct),
                      mm(r.tuned_min_m), mm(r.tuned_median_m), mm(r.tuned_max_m)});
  return t;
}

std::string param_range_text(double value, const ParamRange& range) {
  return fmt::format("{:.3g}{} [{:.3g}, {:.3g}]", value,
                     range.determined ? "" : ", not determined by this recording", range.lo, range.hi);
}

std::vector<GeneralisationRow> generalisation(const std::vector<RunRecord>& runs, ReportMetric metric) {
  std::vector<GeneralisationRow> out;
  const auto tracks = report_tracks(runs);
  for (const auto& model : report_models(runs))
    for (const auto& track : tracks) {
      Mean own, held;
      for (const auto& r : runs) {
        if (r.model != model || r.scored_track() != track) continue;
        (r.is_heldout() ? held : own).add(improvement_pct(r, metric));
      }
      if (own.n && held.n) out.push_back({model, track, own.value(), held.value(), own.n, held.n});
    }
  return out;
}

TextTable text_table(const std::vector<GeneralisationRow>& rows, ReportMetric metric) {
  TextTable t;
  const auto name = metric_name(metric);
  t.header = {"Model", "Track", fmt::format("{} improvement, tuned on this track", name),
              fmt::format("{} improvement, held out (tuned on the other tracks)", name), "Runs"};
  t.numeric = {false, false, true, true, true};
  for (const auto& r : rows)
    t.rows.push_back({r.model, r.track, pct(r.per_track_pct), pct(r.heldout_pct),
                      fmt::format("{} + {}", r.per_track_runs, r.heldout_runs)});
  return t;
}

}  // namespace odotune::results
