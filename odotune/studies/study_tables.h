// The tables of `odotune study resampling` (Table I) and `odotune study
// calibration` (Table II): CSV for machines, text cells for Markdown and the
// terminal, and the Markdown document that states the setup, explains every
// column and sets the paper's values (Fariña, Toledo & Acosta, RA-L 2026,
// Tables I and II) beside ours. Plain study results in, text out.
#pragma once

#include <string>

#include <odotune/results/report_tables.h>
#include <odotune/studies/calibration_study.h>

namespace odotune::studies {

// What the command knows beyond the results, for the Markdown's setup.
struct StudyContext {
  std::string command;             // the command line that regenerates the outputs
  std::string scenario_file;       // as given (or the default's path)
  std::string step_scenario_file;  // calibration study only
  unsigned hardware_threads = 0;   // std::thread::hardware_concurrency()
};

// Numbers in CSV: the shortest form that reads back to the same double, NaN
// as an empty field. Timing columns (ms_per_iter*) come last, so that comparing two runs
// of the same seed can drop them.
std::string csv_number(double v);

// "0.00123 ± 0.00045" (3 and 2 significant digits); "–" when n = 0.
std::string mean_sd_text(const MeanSd& m);

// ---------------------------------------------------------------- Table I
// Header: resampler,policy,runs, then mean,sd pairs of err_rr_m, err_rl_m,
// v_rmse_m_s, w_rmse_rad_s, resampled_fraction, ms_per_iter. One row per cell
// in the study's (the paper's) order.
std::string table1_csv(const ResamplingStudy& s);
// Header: resampler,policy,run,seed,truth_scale_l,truth_scale_r,err_rr_m,
// err_rl_m,v_rmse_m_s,w_rmse_rad_s,resampled_fraction,ms_per_iter.
std::string table1_runs_csv(const ResamplingStudy& s);
// Method | Freq. | Err final R_R [m] | Err final R_L [m] | V RMSE [m/s] |
// W RMSE [rad/s] | resampled [%] | time [ms/iter], mean ± sd.
results::TextTable table1_text(const ResamplingStudy& s);
results::TextTable table1_paper();
std::string table1_markdown(const ResamplingStudy& s, const StudyContext& c);

// ---------------------------------------------------------------- Table II
// Header: track,method,runs, then mean,sd pairs of err_rr_m, err_rl_m,
// err_d_m, pose_rmse_m, heading_rmse_rad, convergence_s (+ converged_runs),
// reached_s (+ reached_runs), reconvergence_s (+ reconverged_runs),
// rereached_s (+ rereached_runs), mean_particles, then ms_per_iter.
std::string table2_csv(const CalibrationStudy& s);
// One row per track × method × run, the same quantities.
std::string table2_runs_csv(const CalibrationStudy& s);
results::TextTable table2_text(const CalibrationStudy& s);
// Online methods only: reached / settled convergence, before and after the
// step, and the final wheel-base error.
results::TextTable table2_convergence_text(const CalibrationStudy& s);
results::TextTable table2_paper();
std::string table2_markdown(const CalibrationStudy& s, const StudyContext& c);

}  // namespace odotune::studies
