#include <odotune/studies/learned_study_outputs.h>

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include <odotune/core/atomic_file.h>
#include <odotune/core/non_finite.h>
#include <odotune/results/gnuplot.h>
#include <odotune/results/learned_figures.h>
#include <odotune/results/learned_model_json.h>
#include <odotune/sim/slip_episodes.h>

namespace odotune::studies {
namespace fs = std::filesystem;

namespace {

using core::kNaN;

// ---------------------------------------------------------------- metric blocks

enum class Metric { mae, rmse, r2, nees_odom, nees_filter };
constexpr int kColumns = 4;  // V, W, X-Y, θ
const char* const kColumnHeaders[kColumns] = {"V (m/s)", "W (rad/s)", "X-Y (m)", "θ (rad)"};
const char* const kColumnCsv[kColumns] = {"V_m_s", "W_rad_s", "XY_m", "theta_rad"};

const char* metric_label(Metric m) {
  switch (m) {
    case Metric::mae: return "MAE";
    case Metric::rmse: return "RMSE";
    case Metric::r2: return "R²";
    case Metric::nees_odom: return "NEES_Odom";
    case Metric::nees_filter: return "NEES_Filter";
  }
  return "";
}
const char* metric_csv(Metric m) {
  switch (m) {
    case Metric::mae: return "mae";
    case Metric::rmse: return "rmse";
    case Metric::r2: return "r2";
    case Metric::nees_odom: return "nees_odom";
    case Metric::nees_filter: return "nees_filter";
  }
  return "";
}

// One method's values of one metric per column (NaN: does not apply).
using Values = std::array<double, kColumns>;

Values values_of(const learned::OdometryErrors& e, Metric m) {
  switch (m) {
    case Metric::mae: return {e.v.mae, e.w.mae, e.xy.mae, e.theta.mae};
    case Metric::rmse: return {e.v.rmse, e.w.rmse, e.xy.rmse, e.theta.rmse};
    case Metric::r2: return {e.v.r2, e.w.r2, e.xy.r2, kNaN};  // θ has no R² (paper: "–")
    case Metric::nees_odom:
    case Metric::nees_filter: return {e.v.nees, e.w.nees, kNaN, kNaN};
  }
  return {kNaN, kNaN, kNaN, kNaN};
}

struct MethodValues {
  std::string method;
  std::vector<std::pair<Metric, Values>> rows;
};

// Is a better than b for this metric? MAE/RMSE: lower; R²: higher; NEES:
// closer to 1 (a variance consistent with the errors, paper eq. 10 per
// dimension).
bool better(Metric m, double a, double b) {
  switch (m) {
    case Metric::r2: return a > b;
    case Metric::nees_odom:
    case Metric::nees_filter: return std::abs(std::log(a)) < std::abs(std::log(b));
    default: return a < b;
  }
}

std::string cell(double v) { return std::isfinite(v) ? fmt::format("{:.4g}", v) : "–"; }

// The paper's layout: method | metric | V | W | X-Y | θ, best per column and
// metric in bold.
results::TextTable metric_table(const std::vector<MethodValues>& methods) {
  results::TextTable t;
  t.header = {"", "", kColumnHeaders[0], kColumnHeaders[1], kColumnHeaders[2], kColumnHeaders[3]};
  t.numeric = {false, false, true, true, true, true};
  for (const MethodValues& mv : methods)
    for (std::size_t r = 0; r < mv.rows.size(); ++r) {
      const auto& [metric, vals] = mv.rows[r];
      std::vector<std::string> row = {r == 0 ? mv.method : "", metric_label(metric)};
      for (int c = 0; c < kColumns; ++c) {
        const double v = vals[static_cast<std::size_t>(c)];
        bool best = std::isfinite(v) && methods.size() > 1;
        for (const MethodValues& other : methods)
          for (const auto& [m2, v2] : other.rows)
            if (m2 == metric && &other != &mv && std::isfinite(v2[static_cast<std::size_t>(c)]) &&
                better(metric, v2[static_cast<std::size_t>(c)], v))
              best = false;
        row.push_back(best ? "**" + cell(v) + "**" : cell(v));
      }
      t.rows.push_back(std::move(row));
    }
  return t;
}

std::string csv_num(double v) { return std::isfinite(v) ? fmt::format("{}", v) : ""; }

std::string metric_csv_rows(const std::string& prefix, const MethodValues& mv, const std::string& suffix) {
  std::string out;
  for (const auto& [metric, vals] : mv.rows) {
    out += prefix + mv.method + "," + metric_csv(metric);
    for (double v : vals) out += "," + csv_num(v);
    out += suffix + "\n";
  }
  return out;
}

MethodValues table1_method(const ErrorRow& r) {
  return {r.name,
          {{Metric::mae, values_of(r.errors, Metric::mae)},
           {Metric::rmse, values_of(r.errors, Metric::rmse)},
           {Metric::r2, values_of(r.errors, Metric::r2)}}};
}

MethodValues table2_method(const Table2Row& r, bool after) {
  const learned::OdometryErrors& e = after ? r.after : r.whole;
  return {r.name,
          {{Metric::mae, values_of(e, Metric::mae)},
           {Metric::rmse, values_of(e, Metric::rmse)},
           {Metric::r2, values_of(e, Metric::r2)}}};
}

MethodValues table3_method(const Table3Row& r) {
  return {r.name,
          {{Metric::mae, values_of(r.filter, Metric::mae)},
           {Metric::rmse, values_of(r.filter, Metric::rmse)},
           {Metric::r2, values_of(r.filter, Metric::r2)},
           {Metric::nees_odom, values_of(r.odometry, Metric::nees_odom)},
           {Metric::nees_filter, values_of(r.filter, Metric::nees_filter)}}};
}

// ---------------------------------------------------------------- JSON

nlohmann::json num_json(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json series_json(const learned::SeriesErrors& s) {
  return {{"mae", num_json(s.mae)},
          {"rmse", num_json(s.rmse)},
          {"r2", num_json(s.r2)},
          {"nees", num_json(s.nees)},
          {"samples", s.samples}};
}

nlohmann::json net_summary_json(const learned::LstmTrainingSummary& s) {
  return {{"iterations", s.iterations},
          {"train_mae", num_json(s.train_mae)},
          {"validation_mae", num_json(s.validation_mae)},
          {"initial_cost", num_json(s.initial_cost)},
          {"final_cost", num_json(s.final_cost)},
          {"termination", s.termination},
          {"usable", s.usable}};
}

nlohmann::json episodes_json(const std::vector<sim::SlipEpisode>& eps) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& e : eps)
    a.push_back({{"kind", std::string(sim::kind_name(e.kind))},
                 {"wheel", std::string(sim::wheel_name(e.wheel))},
                 {"t0_s", e.t0_s},
                 {"t1_s", e.t1_s},
                 {"s", e.s}});
  return a;
}

// ---------------------------------------------------------------- figures

// Mean of |e| over a centred window of `half`·2 + 1 steps (NaN skipped), to
// make a 10 Hz error readable over minutes.
std::vector<double> moving_mean(const std::vector<double>& e, std::size_t half) {
  std::vector<double> out(e.size(), kNaN);
  for (std::size_t k = 0; k < e.size(); ++k) {
    double sum = 0.0;
    int n = 0;
    for (std::size_t j = k > half ? k - half : 0; j <= std::min(e.size() - 1, k + half); ++j)
      if (std::isfinite(e[j])) {
        sum += e[j];
        ++n;
      }
    if (n > 0) out[k] = sum / n;
  }
  return out;
}

void slip_variance_figure(const LearnedStudy& s, const fs::path& stem) {
  const Table3Result& t = s.table3;
  const Table3Row& var = t.rows.at(0);
  std::vector<results::ShadedPanel> panels;
  for (const bool w : {true, false}) {
    results::ShadedPanel p;
    p.ylabel = w ? "variance of W [(rad/s)²]" : "variance of V [(m/s)²]";
    p.log_y = true;
    p.y_min = 0.1 * (w ? s.detector.floor_var_w : s.detector.floor_var_v);
    p.lines.push_back({"(LSTM odometry − truth)²", t.t_s, w ? t.lstm_sq_error_w : t.lstm_sq_error_v, 9, false,
                       true});
    p.lines.push_back({"detector variance (LSTM)", t.t_s, w ? var.odo_var_w : var.odo_var_v, 3, false, false});
    const double stat = w ? s.static_var_lstm_w : s.static_var_lstm_v;
    p.lines.push_back({"static variance (LSTM)", {t.t_s.front(), t.t_s.back()}, {stat, stat}, 0, true, false});
    panels.push_back(std::move(p));
  }
  std::vector<results::TimeShade> shades;
  for (const auto& e : t.episodes) shades.push_back({e.t0_s, e.t1_s});
  results::shaded_time_panels(
      stem, fmt::format("Slip detector on {}: odometry variance over time (Fig. 6 analogue)", t.track), panels,
      shades, "slip episode", {});
}

void retraining_error_figure(const LearnedStudy& s, const fs::path& stem) {
  const Table2Result& t = s.table2;
  constexpr std::size_t kHalf = 5;  // 11 steps: ~1 s at 10 Hz
  const double window_s = static_cast<double>(2 * kHalf + 1) / s.options.rate_hz;
  std::vector<results::ShadedPanel> panels;
  for (const bool w : {true, false}) {
    results::ShadedPanel p;
    p.ylabel = fmt::format("|{} error| [{}], {:.3g} s mean", w ? "W" : "V", w ? "rad/s" : "m/s", window_s);
    const int colours[] = {2, 6, 0};
    // The rows drawn last first, so that "LSTM retraining" lies on top of
    // "no retraining" where the two agree (before the first refit).
    for (std::size_t r = t.rows.size(); r-- > 0;)
      p.lines.push_back({t.rows[r].name, t.t_s,
                         moving_mean(w ? t.rows[r].w_abs_error : t.rows[r].v_abs_error, kHalf), colours[r % 3],
                         false, r == 2});
    panels.push_back(std::move(p));
  }
  std::vector<results::TimeMarker> markers = {{t.change_t_s, "radius change"}};
  for (std::size_t i = 0; i < t.retrains.size(); ++i)
    markers.push_back({t.retrains[i].t_s, i == 0 ? "retrain" : ""});
  results::shaded_time_panels(
      stem, fmt::format("Odometry error on {} with and without online retraining (Fig. 7 analogue)", t.track),
      panels, {}, "", markers);
}

void paths_figure(const LearnedStudy& s, const fs::path& stem) {
  results::PathPanel p1{fmt::format("Table 1, {}: odometry alone", s.table1.track), {}};
  p1.lines = {{"ground truth", s.table1.truth.x, s.table1.truth.y, -1, false},
              {"LSTM odometry", s.table1.lstm.x, s.table1.lstm.y, 2, false},
              {"traditional odometry", s.table1.traditional.x, s.table1.traditional.y, 0, false}};
  results::PathPanel p3{fmt::format("Table 3, {}: UKF output", s.table3.track), {}};
  p3.lines.push_back({"ground truth", s.table3.truth.x, s.table3.truth.y, -1, false});
  const int colours[] = {3, 0, 4};
  for (std::size_t r = 0; r < s.table3.rows.size(); ++r)
    p3.lines.push_back({"UKF, " + s.table3.rows[r].name, s.table3.rows[r].path.x, s.table3.rows[r].path.y,
                        colours[r % 3], r == 2});
  results::path_panels(stem, "XY paths (Figs. 8 and 10 analogues)", {p1, p3});
}

}  // namespace

nlohmann::json errors_json(const learned::OdometryErrors& e) {
  return {{"v", series_json(e.v)},
          {"w", series_json(e.w)},
          {"xy", series_json(e.xy)},
          {"theta", series_json(e.theta)},
          {"nees_vw", num_json(e.nees_vw)}};
}

nlohmann::json flat_errors_json(const learned::OdometryErrors& e) {
  return {{"v_mae", num_json(e.v.mae)},
          {"w_mae", num_json(e.w.mae)},
          {"v_rmse", num_json(e.v.rmse)},
          {"w_rmse", num_json(e.w.rmse)},
          {"v_r2", num_json(e.v.r2)},
          {"w_r2", num_json(e.w.r2)},
          {"pos_mae_m", num_json(e.xy.mae)},
          {"pos_rmse_m", num_json(e.xy.rmse)},
          {"pos_r2", num_json(e.xy.r2)},
          {"pos_rmse_10s_m", num_json(e.xy_rmse_10s)},
          {"pos_rmse_60s_m", num_json(e.xy_rmse_60s)},
          {"theta_mae_rad", num_json(e.theta.mae)},
          {"theta_rmse_rad", num_json(e.theta.rmse)},
          {"samples", e.v.samples}};
}

results::TextTable learned_table1_text(const LearnedStudy& s) {
  std::vector<MethodValues> m;
  for (const ErrorRow& r : s.table1.rows) m.push_back(table1_method(r));
  return metric_table(m);
}

results::TextTable learned_table2_text(const LearnedStudy& s, bool after_change) {
  std::vector<MethodValues> m;
  for (const Table2Row& r : s.table2.rows) m.push_back(table2_method(r, after_change));
  return metric_table(m);
}

results::TextTable learned_table2_cost_text(const LearnedStudy& s) {
  results::TextTable t;
  t.header = {"", "retrains", "ms per retrain"};
  t.numeric = {false, true, true};
  for (const Table2Row& r : s.table2.rows)
    t.rows.push_back({r.name, r.name == "LSTM retraining" ? std::to_string(r.retrains) : "–",
                      std::isfinite(r.ms_per_retrain) ? fmt::format("{:.1f}", r.ms_per_retrain) : "–"});
  return t;
}

results::TextTable learned_table3_text(const LearnedStudy& s) {
  std::vector<MethodValues> m;
  for (const Table3Row& r : s.table3.rows) m.push_back(table3_method(r));
  return metric_table(m);
}

std::string learned_table1_csv(const LearnedStudy& s) {
  std::string out = "method,metric,V_m_s,W_rad_s,XY_m,theta_rad\n";
  for (const ErrorRow& r : s.table1.rows) out += metric_csv_rows("", table1_method(r), "");
  return out;
}

std::string learned_table2_csv(const LearnedStudy& s) {
  std::string out = "block,method,metric,V_m_s,W_rad_s,XY_m,theta_rad,retrains,ms_per_retrain\n";
  for (const bool after : {true, false})
    for (const Table2Row& r : s.table2.rows)
      out += metric_csv_rows(after ? "after_change," : "whole_track,", table2_method(r, after),
                             fmt::format(",{},{}", r.retrains, csv_num(r.ms_per_retrain)));
  return out;
}

std::string learned_table3_csv(const LearnedStudy& s) {
  std::string out = "method,metric,V_m_s,W_rad_s,XY_m,theta_rad\n";
  for (const Table3Row& r : s.table3.rows) out += metric_csv_rows("", table3_method(r), "");
  return out;
}

nlohmann::json learned_results_json(const LearnedStudy& s, const LearnedStudyContext& c) {
  const LearnedStudyOptions& o = s.options;
  nlohmann::json j;
  j["format"] = "odotune-study-learned/1";
  j["options"] = {{"seed", o.seed},
                  {"iterations", o.iterations},
                  {"retrain_iterations", o.retrain_iterations},
                  {"samples_per_retrain", o.samples_per_retrain},
                  {"rate_hz", o.rate_hz},
                  {"previous_noise_v", o.previous_noise_v},
                  {"previous_noise_w", o.previous_noise_w},
                  {"slip_drives", o.slip_drives},
                  {"slip_stride", o.slip_stride}};
  nlohmann::json drives = nlohmann::json::array();
  for (const LearnedStudy::SlipDrive& d : s.slip_drives)
    drives.push_back({{"seed", d.seed}, {"slip_episodes", sim::format_slip_episodes(d.episodes)}});
  j["slip_training_drives"] = drives;
  nlohmann::json sc = nlohmann::json::array();
  for (std::size_t i = 0; i < s.scenario_names.size(); ++i)
    sc.push_back({{"role", kLearnedScenarioRoles[i]},
                  {"scenario", s.scenario_names[i]},
                  {"file", i < c.scenario_files.size() ? c.scenario_files[i] : ""},
                  {"seed", o.seed + i},
                  {"track", s.track_names.at(i)}});
  j["scenarios"] = sc;
  const TrainingRecord& t = s.training;
  j["training"] = {{"odometry",
                    {{"v", net_summary_json(t.odometry.v)},
                     {"w", net_summary_json(t.odometry.w)},
                     {"train_windows", t.odometry.train_windows},
                     {"validation_windows", t.odometry.validation_windows}}},
                   {"detector",
                    {{"v", net_summary_json(t.detector.v)},
                     {"w", net_summary_json(t.detector.w)},
                     {"train_windows", t.detector.train_windows},
                     {"validation_windows", t.detector.validation_windows}}},
                   {"kinematic_v_mae", num_json(t.kinematic_v_mae)},
                   {"kinematic_w_mae", num_json(t.kinematic_w_mae)}};
  j["static_variance"] = {{"lstm_v", s.static_var_lstm_v},
                          {"lstm_w", s.static_var_lstm_w},
                          {"kinematic_v", s.static_var_kin_v},
                          {"kinematic_w", s.static_var_kin_w},
                          {"gyro", s.static_var_gyro}};
  nlohmann::json t1 = nlohmann::json::array();
  for (const ErrorRow& r : s.table1.rows) t1.push_back({{"method", r.name}, {"errors", errors_json(r.errors)}});
  j["table1"] = {{"track", s.table1.track}, {"rows", t1}};
  nlohmann::json t2 = nlohmann::json::array();
  for (const Table2Row& r : s.table2.rows)
    t2.push_back({{"method", r.name},
                  {"whole", errors_json(r.whole)},
                  {"after_change", errors_json(r.after)},
                  {"retrains", r.retrains}});
  nlohmann::json ev = nlohmann::json::array();
  for (const RetrainRecord& r : s.table2.retrains)
    ev.push_back({{"step", r.step},
                  {"t_s", r.t_s},
                  {"v_cost_before", num_json(r.v_cost_before)},
                  {"v_cost_after", num_json(r.v_cost_after)},
                  {"v_mae_after", num_json(r.v_mae_after)},
                  {"w_cost_before", num_json(r.w_cost_before)},
                  {"w_cost_after", num_json(r.w_cost_after)},
                  {"w_mae_after", num_json(r.w_mae_after)},
                  {"v_iterations", r.v_iterations},
                  {"w_iterations", r.w_iterations}});
  j["table2"] = {{"track", s.table2.track},
                 {"change_t_s", s.table2.change_t_s},
                 {"change_step", s.table2.change_step},
                 {"rows", t2},
                 {"retrains", ev}};
  nlohmann::json t3 = nlohmann::json::array();
  for (const Table3Row& r : s.table3.rows)
    t3.push_back({{"method", r.name},
                  {"filter", errors_json(r.filter)},
                  {"odometry", errors_json(r.odometry)},
                  {"healthy", r.healthy}});
  j["table3"] = {{"track", s.table3.track}, {"slip_episodes", episodes_json(s.table3.episodes)}, {"rows", t3}};
  return j;
}

std::vector<fs::path> write_learned_outputs(const LearnedStudy& s, const LearnedStudyContext& c,
                                            const fs::path& dir) {
  std::vector<fs::path> files;
  const auto text = [&](const std::string& name, const std::string& content) {
    core::write_atomically(dir / name, "study output", content);
    files.push_back(dir / name);
  };
  std::string setup = fmt::format(
      "Seed {} (scenario i simulated with seed {} + i), {} Ceres iterations per training, {} per retrain every {} "
      "samples, {} Hz.\nRegenerate: `{}`\n",
      s.options.seed, s.options.seed, s.options.iterations, s.options.retrain_iterations,
      s.options.samples_per_retrain, s.options.rate_hz, c.command);

  text("table1.csv", learned_table1_csv(s));
  text("table1.md", fmt::format("# Table 1: LSTM vs traditional odometry on {}\n\n{}\n{}", s.table1.track,
                                results::to_markdown(learned_table1_text(s)), setup));
  text("table2.csv", learned_table2_csv(s));
  text("table2.md",
       fmt::format("# Table 2: odometry fed to the UKF on {}, radius change at {:g} s\n\n"
                   "## After the radius change (pose dead-reckoned from the true pose at {:g} s)\n\n{}\n"
                   "## Whole track\n\n{}\n## Retraining cost\n\n{}\n{}",
                   s.table2.track, s.table2.change_t_s, s.table2.change_t_s,
                   results::to_markdown(learned_table2_text(s, true)),
                   results::to_markdown(learned_table2_text(s, false)),
                   results::to_markdown(learned_table2_cost_text(s)), setup));
  text("table3.csv", learned_table3_csv(s));
  text("table3.md",
       fmt::format("# Table 3: UKF output on {} (slip episodes), variable vs static odometry covariance\n\n{}\n"
                   "NEES per dimension (e²/variance averaged; 1 = consistent); bold = closest to 1.\n\n{}",
                   s.table3.track, results::to_markdown(learned_table3_text(s)), setup));
  text("results.json", learned_results_json(s, c).dump(2) + "\n");

  nlohmann::json timing;
  timing["study_s"] = s.wall_s;
  timing["odometry_training_s"] = s.training.odometry.seconds;
  timing["detector_training_s"] = s.training.detector.seconds;
  nlohmann::json ms = nlohmann::json::array();
  for (const RetrainRecord& r : s.table2.retrains) ms.push_back(r.ms);
  timing["retrain_ms"] = ms;
  text("timing.json", timing.dump(2) + "\n");

  results::LearnedModelFile model;
  model.odometry = s.model;
  model.detector = s.detector;
  results::LearnedModelProvenance& p = model.provenance;
  p.tracks = {s.track_names.at(0)};
  p.slip_tracks = {s.track_names.at(3)};
  p.seed = s.options.seed;
  p.odometry = results::training_record(s.training.odometry.v, s.training.odometry.w,
                                        s.training.odometry.train_windows,
                                        s.training.odometry.validation_windows, s.training.odometry.seconds);
  p.detector = results::training_record(s.training.detector.v, s.training.detector.w,
                                        s.training.detector.train_windows,
                                        s.training.detector.validation_windows, s.training.detector.seconds);
  p.created_by = c.command;
  results::write_learned_model(dir / "model.json", model);
  files.push_back(dir / "model.json");

  fs::path stem = dir / "fig_slip_variance";
  slip_variance_figure(s, stem);
  results::append_png_svg(stem, &files);
  stem = dir / "fig_retraining_error";
  retraining_error_figure(s, stem);
  results::append_png_svg(stem, &files);
  stem = dir / "fig_paths";
  paths_figure(s, stem);
  results::append_png_svg(stem, &files);
  return files;
}

}  // namespace odotune::studies
