// The study behind `odotune study learned`: Tables 1–3 of Fariña, Acosta,
// Toledo & Acosta, "Improving Odometric Model Performance Based on LSTM
// Networks", Sensors 2023, 23, 961 (../shared/papers/002_*.txt, §5), on
// simulated wheelchair tracks (scenarios/wheelchair_learn*.yaml,
// wheelchair_slip*.yaml). Computation only: scenarios and options in, plain
// numbers and series out; `study_runs.h` reads the scenario files,
// `odotune/cli/cmd_study.cpp` prints,
// `learned_study_outputs.h` writes tables, JSON and figures.
//
// Steps (every one seeded; the same seed gives the same numbers):
//   1. Simulate the five scenarios, scenario i with seed options.seed + i
//      (i = 0 learn, 1 eval, 2 step, 3 slip, 4 slip_eval), so that training
//      and evaluation tracks never share sensor noise; lay each out at
//      options.rate_hz (odotune/learned/fusion_input.h).
//      Then options.slip_drives − 1 more drives of the `slip` route, drive j
//      (1-based) with seed options.seed + 4 + j and the random episode
//      layout random_slip_episodes(route, seed + 4 + j) in place of the
//      scenario's own episodes.
//   2. Train the velocity nets on `learn` (train_learned_odometry, 70/30
//      split, Ceres seed options.seed) and the slip detector on `slip` and
//      the extra drives, against the learned odometry's errors there
//      (run_learned_odometry).
//   3. Static odometry variances ("manually adjusted" in the paper): each
//      odometry's mean squared velocity error over the detector's training
//      drives — the best constant variance for a track with slip; and the
//      gyro's the same way (its bias and scale error make it more than the
//      sensor's white noise), used for every row of Table 3.
//   4. Table 1 on `eval`: learned vs kinematic odometry alone, pose
//      dead-reckoned from each.
//   5. Table 2 on `step` (a radius_step mid-drive): the UKF (external
//      velocities + gyro) fed the learned odometry with retraining, without,
//      and the kinematic odometry; scored is the ODOMETRY the UKF was fed
//      (pose dead-reckoned from it), over the whole track and after the
//      change (re-reckoned from the true pose at the change).
//   6. Table 3 on `slip_eval`: the UKF output with learned odometry +
//      detector variance, kinematic + static variance, and (ablation) learned
//      + static variance; NEES of the odometry (with its variance) and of the
//      filter (with its covariance) per V and W.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <odotune/learned/fusion_input.h>
#include <odotune/learned/learned_fusion.h>
#include <odotune/learned/learned_odometry.h>
#include <odotune/learned/odometry_metrics.h>
#include <odotune/learned/slip_detector.h>
#include <odotune/sim/scenario.h>

namespace odotune::studies {

struct LearnedStudyOptions {
  std::uint64_t seed = 1;       // scenario i simulated with seed + i; Ceres initial weights
  int iterations = 100;         // Ceres iterations of each initial training (velocity nets, detector), 1..10000
  int retrain_iterations = 10;  // Ceres iterations of each online retrain (paper §4.2), 1..10000
  int samples_per_retrain = 300;  // paper §4.2, 20..100000
  double rate_hz = 10.0;          // fusion / network rate (paper: 10 Hz), (0, 1000]
  // Noise on the teacher-forced previous velocity while training [m/s, rad/s]
  // (LearnedTrainingOptions), ≥ 0. 0: on short simulated drives 0.02 made the
  // V net's validation MAE worse, not better (tried with `learn train
  // --previous-noise`).
  double previous_noise_v = 0.0, previous_noise_w = 0.0;
  // Drives the slip detector trains on: `slip` as written, and slip_drives − 1
  // more of the same route with random episode layouts (odotune/sim/random_slip.h),
  // 1..20. One drive teaches the detector its ten episodes, not slip: trained
  // on wheelchair_slip alone it missed episodes of the held-out drive.
  int slip_drives = 4;
  int slip_stride = 1;  // every n-th detector window (SlipTrainingOptions::stride), ≥ 1
  int threads = 1;      // OpenMP threads evaluating the windows; results do not depend on it, ≥ 1
  bool IsValid(std::string* why) const;
};

struct LearnedStudyScenarios {
  sim::Scenario learn, eval, step, slip, slip_eval;
};

// The scenario roles in simulation order (seed offset = index).
inline constexpr const char* kLearnedScenarioRoles[] = {"learn", "eval", "step", "slip", "slip_eval"};

// Throws std::invalid_argument (one line naming the role and scenario) when a
// scenario cannot serve: invalid, no encoders, no ground truth; `step`
// without radius_step; `slip`/`slip_eval` without motor power or slip
// episodes; `step`, `slip`, `slip_eval` without external velocity or gyro.
void check_learned_scenarios(const LearnedStudyScenarios& s);

// A pose path for the figures [m, m, rad].
struct PathSeries {
  std::vector<double> x, y, theta;
};

struct ErrorRow {
  std::string name;  // the paper's row label
  learned::OdometryErrors errors;
};

// ---------------------------------------------------------------- Table 1
struct Table1Result {
  std::string track;
  std::vector<ErrorRow> rows;  // "LSTM odometry", "Traditional odometry"
  PathSeries truth, lstm, traditional;
};

// ---------------------------------------------------------------- Table 2
struct Table2Row {
  std::string name;               // "LSTM retraining", "LSTM no retraining", "Traditional odometry"
  learned::OdometryErrors whole;  // the whole track
  learned::OdometryErrors after;  // from the radius change on (pose re-reckoned from the true pose there)
  int retrains = 0;               // online refits
  double ms_per_retrain = std::numeric_limits<double>::quiet_NaN();  // mean wall time of one refit (timing)
  std::vector<double> v_abs_error, w_abs_error;  // |odometry − truth| per step (NaN without truth)
};

struct RetrainRecord {
  std::size_t step = 0;
  double t_s = 0.0;
  double ms = 0.0;  // timing
  // RetrainEvent gives no MAE before the refit: the Ceres cost (½ Σ ρ over the
  // samples, standardised units) before and after, and the MAE after [m/s, rad/s].
  double v_cost_before = 0.0, v_cost_after = 0.0, v_mae_after = 0.0;
  double w_cost_before = 0.0, w_cost_after = 0.0, w_mae_after = 0.0;
  int v_iterations = 0, w_iterations = 0;
};

struct Table2Result {
  std::string track;
  double change_t_s = 0.0;      // the radius_step time [s]
  std::size_t change_step = 0;  // first step at or after it
  std::vector<double> t_s;      // step times
  std::vector<Table2Row> rows;
  std::vector<RetrainRecord> retrains;  // of the retraining row
  PathSeries truth;                     // for completeness of results.json
};

// ---------------------------------------------------------------- Table 3
struct Table3Row {
  std::string name;                  // "LSTM odometry + variable covariance", ...
  learned::OdometryErrors filter;    // UKF output (V, W and its integrated pose); v/w.nees = NEES_Filter
  learned::OdometryErrors odometry;  // the odometry fed to it with its variance; v/w.nees = NEES_Odom
  bool healthy = true;
  PathSeries path;                           // UKF pose
  std::vector<double> odo_var_v, odo_var_w;  // the odometry variance fed [(m/s)², (rad/s)²]
};

struct Table3Result {
  std::string track;
  std::vector<Table3Row> rows;
  std::vector<double> t_s;
  std::vector<sim::SlipEpisode> episodes;                // the slip_eval scenario's
  std::vector<double> lstm_sq_error_v, lstm_sq_error_w;  // (LSTM odometry − truth)² per step
  PathSeries truth;
};

struct TrainingRecord {
  learned::LearnedTrainingSummary odometry;
  learned::SlipTrainingSummary detector;
  double kinematic_v_mae = 0.0, kinematic_w_mae = 0.0;  // on the learn track, for comparison
};

struct LearnedStudy {
  LearnedStudyOptions options;
  std::vector<std::string> scenario_names;  // kLearnedScenarioRoles order
  std::vector<std::string> track_names;     // the simulated tracks' names
  // The detector's training drives: `slip` then the random layouts (step 1).
  struct SlipDrive {
    std::uint64_t seed = 0;
    std::vector<sim::SlipEpisode> episodes;
  };
  std::vector<SlipDrive> slip_drives;
  learned::LearnedOdometryModel model;
  learned::SlipDetectorModel detector;
  TrainingRecord training;
  double static_var_lstm_v = 0.0, static_var_lstm_w = 0.0;  // step 3 [(m/s)², (rad/s)²]
  double static_var_kin_v = 0.0, static_var_kin_w = 0.0;
  // The gyro's static variance in Table 3's fusion: its mean squared error
  // (gyro_z − true W) over the detector's training drives; the UKF default
  // (UkfSensorNoise::gyro_var) when they have no gyro [(rad/s)²].
  double static_var_gyro = learned::UkfSensorNoise{}.gyro_var;
  Table1Result table1;
  Table2Result table2;
  Table3Result table3;
  double wall_s = 0.0;  // timing
};

// Progress: (stage done, stages total) and the stage's name.
using LearnedStudyProgress = std::function<void(long done, long total, const std::string& stage)>;

// Throws std::invalid_argument for invalid options or scenarios (one line).
LearnedStudy run_learned_study(const LearnedStudyScenarios& scenarios, const LearnedStudyOptions& options,
                               const LearnedStudyProgress& progress = {});

// ---------------------------------------------------------------- helpers shared with `learn`

// The steps [first, size) of `in` as an input of their own (step 0 of the
// slice = step first − 1 of `in`, its per-step values zeroed as build_fusion_input
// does for step 0), so that odometry_errors re-reckons the pose from the true
// pose there. Throws std::invalid_argument when fewer than 2 steps remain.
learned::FusionInput slice_fusion_input(const learned::FusionInput& in, std::size_t first);
// The same slice of a per-step series.
std::vector<double> slice_series(const std::vector<double>& v, std::size_t first);

// Errors of an odometry series alone (pose dead-reckoned from it).
learned::OdometryErrors odometry_only_errors(const learned::FusionInput& in,
                                             const learned::OdometrySeries& odo);

// |est − truth| per step; NaN where either is not finite.
std::vector<double> abs_errors(const std::vector<double>& est, const std::vector<double>& truth);

// Mean squared error of a series against truth over steps ≥ 1 [unit²];
// NaN without samples.
double mean_squared_error(const std::vector<double>& est, const std::vector<double>& truth);

}  // namespace odotune::studies
