// The Monte-Carlo studies behind `odotune study resampling` (Table I) and
// `odotune study calibration` (Table II) of Fariña, Toledo & Acosta, "A New
// Approach to Real-Time Odometry Calibration Using an Adaptive Particle
// Filter Design" (RA-L 2026, ../shared/papers/000_*.txt, §IV–VI), on
// simulated wheelchair tracks (scenarios/wheelchair*.yaml). Computation only:
// scenarios and options in, plain numbers out; `study_runs.h` reads the
// scenario files and writes the outputs, `odotune/cli/cmd_study.cpp` prints, `study_tables.h` and `odotune/results/study_figures.h` format.
//
// Monte-Carlo run r (0-based) uses seed s_r = options.seed + r for
//   * the simulated track's sensor noise (Scenario::seed = s_r);
//   * the truth: radius_error's scales redrawn uniformly in
//     [1 − spread, 1 + spread] (the scenario's other effects, wheel_base_error
//     and radius_step included, are kept);
//   * the filters: PF particles uniform in PfCalibratorParams' default ranges
//     (seed s_r); the DKF's initial radii drawn uniformly in those same
//     ranges (its initial wheel base is the nominal one).
// The same run r shares its track, truth and PF seed across every cell and
// method (common random numbers), so differences between cells are the
// methods', not the draws'.
//
// Runs × cells are spread over OpenMP threads; each task owns its filter and
// runs it single-threaded, so every number except the timing columns is
// bit-identical for any thread count. Timing (ms per iteration) is wall time
// measured while the other threads run their own tasks.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <odotune/calibration/calibration_input.h>
#include <odotune/calibration/calibration_run.h>
#include <odotune/filters/odometry_params.h>
#include <odotune/filters/resampling.h>
#include <odotune/sim/scenario.h>

namespace odotune::studies {

// Mean and sample standard deviation (n − 1 in the denominator) of the
// finite values; NaN values are skipped (they count neither in n nor in the
// statistics). n = 1: sd = 0; n = 0: mean = sd = NaN.
struct MeanSd {
  double mean = std::numeric_limits<double>::quiet_NaN();
  double sd = std::numeric_limits<double>::quiet_NaN();
  int n = 0;
};
MeanSd mean_sd(const std::vector<double>& values);

struct StudyOptions {
  // Monte-Carlo runs, 1..1000. 20: a default Table I (240 PF runs of 5000
  // particles over 2 minutes of track) takes about a minute on 2 cores.
  int runs = 20;
  std::uint64_t seed = 1;             // run r uses seed + r
  int threads = 0;                    // OpenMP threads over runs × cells; 0 = OpenMP's default
  double truth_radius_spread = 0.02;  // per run: radius_error scales ~ U(1 − spread, 1 + spread), (0, 0.1]
  int pf_particles = 5000;            // N of the plain PF in Table I (the paper's 5000), 10..1000000
  // Adaptive PF of Table II: initial N (the paper's 8000; 0 = adaptive_defaults()).
  int adaptive_initial_particles = 0;

  // True when usable; otherwise *why names the first bad value
  // ("runs = 0 must be in 1..1000").
  bool IsValid(std::string* why) const;
};

// What Monte-Carlo run r draws (see the file comment).
struct McDraw {
  int run = 0;
  std::uint64_t seed = 0;      // options.seed + run
  double truth_scale_l = 1.0;  // radius_error.scale_l of this run's truth
  double truth_scale_r = 1.0;
  filters::OdometryParams dkf_initial;  // DKF's initial radii (and nominal base)
};
McDraw mc_draw(const StudyOptions& options, const sim::Scenario& scenario, int run);

// The scenario of run r: seed s_r and the drawn radius_error (other effects kept).
sim::Scenario run_scenario(const sim::Scenario& scenario, const McDraw& draw);

// Throws std::invalid_argument (one line naming the scenario) when the
// scenario cannot serve a study: invalid, no encoders / external velocity /
// ground truth, or a possible truth radius (nominal × (1 ± spread) × any
// radius_step scale) outside the PF's initial ranges.
void check_study_scenario(const sim::Scenario& scenario, const StudyOptions& options);

// Progress of a study: (tasks done, tasks total); called from one thread at a
// time (under a lock), possibly from different threads.
using StudyProgress = std::function<void(long done, long total)>;

// ---------------------------------------------------------------- Table I

// One plain-PF run of one resampler × policy cell.
struct ResamplingRunResult {
  double err_rr_m = 0.0;            // |final R_R − true R_R| [m]
  double err_rl_m = 0.0;            // |final R_L − true R_L| [m]
  double v_rmse_m_s = 0.0;          // RMSE of the calibrated odometry's V vs the truth [m/s]
  double w_rmse_rad_s = 0.0;        // likewise W [rad/s]
  double resampled_fraction = 0.0;  // iterations that resampled / iterations
  double ms_per_iteration = 0.0;    // wall time [ms] (timing: varies run to run)
};

struct ResamplingCell {
  filters::Resampler resampler = filters::Resampler::systematic;
  filters::ResamplePolicy policy = filters::ResamplePolicy::neff;
  std::vector<ResamplingRunResult> runs;  // index = Monte-Carlo run
  MeanSd err_rr_m, err_rl_m, v_rmse_m_s, w_rmse_rad_s, resampled_fraction, ms_per_iteration;
};

struct ResamplingStudy {
  std::string scenario;  // the scenario's name
  StudyOptions options;
  int threads_used = 0;             // OpenMP threads the study ran on
  std::vector<McDraw> draws;        // one per run
  double iterations_per_run = 0.0;  // mean PF iterations (external measurements) per run
  double track_duration_s = 0.0;    // run 0's track, first to last odometry row [s]
  // 12 cells: resamplers in the paper's order (stratified, multinomial,
  // residual, systematic), each with policies neff, max_weight, every_step.
  std::vector<ResamplingCell> cells;
  double wall_s = 0.0;  // the whole study [s] (timing)
};

// The paper's row order of Table I.
std::vector<filters::Resampler> table1_resamplers();
std::vector<filters::ResamplePolicy> table1_policies();

// Throws std::invalid_argument for invalid options or scenario.
ResamplingStudy run_resampling_study(const sim::Scenario& scenario, const StudyOptions& options,
                                     const StudyProgress& progress = {});

// ---------------------------------------------------------------- Table II

// The estimates over time of one online run, for the figures: one entry per
// iteration, t_s on the track's clock.
struct ParamTrace {
  std::vector<double> t_s;
  std::vector<double> r_right_m, r_left_m, wheel_base_m;                 // estimates [m]
  std::vector<double> true_r_right_m, true_r_left_m, true_wheel_base_m;  // the truth at t_s [m]
  std::vector<int> particles;                                            // N (0 for the DKF)
};

// Radii-only convergence (the paper's Table II: "when the error falls below
// 0.5 % of the true value", of the radii; D is not analysed, §IV), per piece
// of the truth schedule, in two readings:
//   reached: the first iteration at which R_R and R_L are both within
//            tolerance·truth (the paper's words taken literally);
//   settled: the earliest iteration after which they stay within it at every
//            later iteration of the piece (objectives' convergence_time(),
//            with D pinned to the truth so that only the radii can decide).
// Piece 0 is measured from `start_s` (the track's first odometry row), piece
// k > 0 from the k-th truth change; NaN: never (or no iteration in the piece).
struct PieceConvergence {
  double reached_s = std::numeric_limits<double>::quiet_NaN();
  double settled_s = std::numeric_limits<double>::quiet_NaN();
};
std::vector<PieceConvergence> radius_convergence(
    const ParamTrace& trace, const calibration::TruthSchedule& truth, double start_s, double tolerance);

struct MethodRunResult {
  double err_rr_m = 0.0, err_rl_m = 0.0;  // |final − true| at the track's end [m]
  double pose_rmse_m = 0.0;               // RMSE(x, y) of the calibrated odometry vs GT [m]
  double heading_rmse_rad = 0.0;          // RMSE θ [rad]
  double err_d_m = 0.0;                   // |final − true| of the wheel base [m]
  // Radii-only convergence (radius_convergence()) [s]; NaN: never, or n.a.
  // (fixed-parameter methods). convergence = settled, reached = first within
  // tolerance; re* = the same after the first truth change.
  double convergence_s = std::numeric_limits<double>::quiet_NaN();
  double reached_s = std::numeric_limits<double>::quiet_NaN();
  double reconvergence_s = std::numeric_limits<double>::quiet_NaN();
  double rereached_s = std::numeric_limits<double>::quiet_NaN();
  double mean_particles = 0.0;    // PF: mean N over iterations
  double ms_per_iteration = 0.0;  // timing
};

// Table II's two simulated tracks: constant wheel geometry, and a step
// change of it (the step scenario).
enum class StudyTrack { constant, step };
inline constexpr std::array<StudyTrack, 2> kAllStudyTracks = {StudyTrack::constant, StudyTrack::step};
std::string_view to_string(StudyTrack t);  // "constant", "step"

struct MethodRow {
  StudyTrack track = StudyTrack::constant;
  calibration::CalibrationMethod method = calibration::CalibrationMethod::none;
  std::vector<MethodRunResult> runs;  // index = Monte-Carlo run
  MeanSd err_rr_m, err_rl_m, err_d_m, pose_rmse_m, heading_rmse_rad, convergence_s, reached_s, reconvergence_s,
      rereached_s, mean_particles, ms_per_iteration;
  bool online = false;    // convergence is defined (adaptive-pf, dkf)
  bool has_step = false;  // the track's truth changes (re-convergence defined)
};

struct CalibrationStudy {
  std::string scenario, step_scenario;  // scenario names
  StudyOptions options;
  int threads_used = 0;
  std::vector<McDraw> draws;
  double step_time_s = std::numeric_limits<double>::quiet_NaN();  // first truth change of the step track
  double track_duration_s = 0.0;       // run 0's constant track, first to last odometry row [s]
  double convergence_tolerance = 0.0;  // fraction of the truth (the paper's 0.5 %)
  // 8 rows: track constant then step, each with adaptive-pf, dkf, batch-velocity, none.
  std::vector<MethodRow> rows;
  // Per run (index = run): the adaptive PF on both tracks and the DKF on both.
  std::vector<ParamTrace> pf_constant, pf_step, dkf_constant, dkf_step;
  double wall_s = 0.0;
};

// The methods of Table II, in its column order.
std::vector<calibration::CalibrationMethod> table2_methods();

// Throws std::invalid_argument for invalid options or scenarios.
CalibrationStudy run_calibration_study(const sim::Scenario& constant, const sim::Scenario& step,
                                       const StudyOptions& options, const StudyProgress& progress = {});

}  // namespace odotune::studies
