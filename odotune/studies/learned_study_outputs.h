// What `odotune study learned` writes into its --out folder, and the JSON
// blocks `odotune learn eval|retrain` share with it. Plain study results in,
// text and files out; every file written atomically (odotune/core/atomic_file.h;
// figures: odotune/results/gnuplot.h, PNG + SVG both or neither).
//
//   table1.md/.csv   learned vs traditional odometry (paper Table 1 layout)
//   table2.md/.csv   odometry with / without retraining after a radius change
//                    (Table 2): two blocks, "after the change" then "whole
//                    track", and the retraining cost
//   table3.md/.csv   UKF with variable vs static odometry covariance on a
//                    track with slip (Table 3), NEES_Odom and NEES_Filter
//   results.json     every number of the study except timing (so that two runs
//                    with one seed give identical files)
//   timing.json      wall times (study, trainings, each retrain)
//   model.json       the trained model (odotune/results/learned_model_json.h)
//   fig_slip_variance, fig_retraining_error, fig_paths (.png + .svg)
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <odotune/learned/odometry_metrics.h>
#include <odotune/results/report_tables.h>
#include <odotune/studies/learned_study.h>

namespace odotune::studies {

// What the command knows beyond the results, for the Markdown's setup.
struct LearnedStudyContext {
  std::string command;                      // regenerates the outputs
  std::vector<std::string> scenario_files;  // kLearnedScenarioRoles order, as displayed
};

// {"v": {mae, rmse, r2, nees, samples}, "w": …, "xy": …, "theta": …, "nees_vw"}
// (NaN → null).
nlohmann::json errors_json(const learned::OdometryErrors& e);
// The flat block of `learn eval`: v_mae, w_mae, v_rmse, w_rmse, v_r2, w_r2,
// pos_mae_m, pos_rmse_m, pos_r2, pos_rmse_10s_m, pos_rmse_60s_m (dead
// reckoning restarted every 10 s and 60 s; null for a filter's pose),
// theta_mae_rad, theta_rmse_rad, samples.
nlohmann::json flat_errors_json(const learned::OdometryErrors& e);

// The tables as text (Markdown cells: best value per column and metric in
// bold; "–" where a metric does not apply).
results::TextTable learned_table1_text(const LearnedStudy& s);
// block "after" (from the radius change on) or "whole" (the whole track).
results::TextTable learned_table2_text(const LearnedStudy& s, bool after_change);
results::TextTable learned_table2_cost_text(const LearnedStudy& s);
results::TextTable learned_table3_text(const LearnedStudy& s);

// CSV: method,metric,V_m_s,W_rad_s,XY_m,theta_rad (table 2 with a leading
// block column and trailing retrains, ms_per_retrain); shortest round-trip
// numbers, empty where not applicable.
std::string learned_table1_csv(const LearnedStudy& s);
std::string learned_table2_csv(const LearnedStudy& s);
std::string learned_table3_csv(const LearnedStudy& s);

nlohmann::json learned_results_json(const LearnedStudy& s, const LearnedStudyContext& c);

// Writes the files listed above into `dir` (which must exist); returns them
// in order of writing. Throws std::runtime_error when a file or figure cannot
// be written.
std::vector<std::filesystem::path> write_learned_outputs(const LearnedStudy& s, const LearnedStudyContext& c,
                                                         const std::filesystem::path& dir);

}  // namespace odotune::studies
