// Experiment files for `odotune grid` (see experiments/*.yaml, commented):
//
//   format: odotune-experiment/1
//   name: study
//   models: [rq, alpha, gyro]            # also pf-calib, adaptive-pf-calib, ukf (odotune/objectives/tuned_model.h)
//   tracks: [../data/tracks/track*.csv]   # paths or globs, relative to this file
//   modes: [1, 2, 3, 4, 5, 6, 7]         # numbers or names (rmse, …, rmse+mae+maxe, fix-rmse, fix-nll)
//   seeds: {first: 1, count: 20}         # or a list: [1, 2, 3]
//   solver: pso                          # or nlopt:NAME
//   budget: {particles: 50, iterations: 150}   # nlopt: {evaluations: 7550}
//   leave_one_out: false                 # also tune on all tracks but one, score on it
//   store: ../results/study.sqlite       # relative to this file
//   calibration:                         # optional; the calibrator models' fixed parts
//     resampler: systematic              # multinomial | stratified | systematic | residual
//     policy: neff                       # every | neff | max
//     particles: 0                       # N / initial N; 0 = the paper's 5000 / 8000
//     seed: 1                            # the particle filter's own seed
//     ext_from_gt_hz: 0                  # > 0: external velocities from the ground truth
//
//   robot_localization:                  # models rl-ekf and rl-ukf only (their tracks are bags)
//     params: husky_ekf.yaml             # the robot's parameter file, relative to this file
//     tf: ["imu_link=0,-0.3,0.52,1.5708,0,-1.5708"]   # FRAME=x,y,z,roll,pitch,yaw [m, rad], quoted
//     navsat_params: navsat.yaml          # optional: navsat_transform_node's own file (--navsat-params)
//     remap: ["odom=/husky_velocity_controller/odom"]   # optional: FROM=TO topic remappings (--remap)
//     gps_heading_fit_s: 60              # fit navsat's rotation on the first seconds of fixes
//     until_s: 197.65                    # required: tune before, score after (held out)
//     end_s: 395                         # optional: the held-out span ends here
//     fitness: [outage, both]            # instead of modes: heldout-fixes, outage, both
//     space: diagonal                    # or blocks
//     input_covariances: false           # also search factors on the inputs' covariances
//     outage_s: [30, 60]                 # the outages' lengths [s]: one, or a list
//     outage_every_s: 10                 # an outage of each length starts every … [s]
//     grid_levels: [-2, 0, 2]            # the search's grid of block factors [decades], or []
//     refine_decades: 0                  # its seeded refinement around the grid's best (0: none)
//     profile_step_decades: 0.5          # the profile's step
//
// A calibrator model (pf-calib, adaptive-pf-calib) has no fitness mode: its
// cells are made for the first listed mode only (the run records that mode),
// so a calibrator run is not repeated per mode. The fusion UKF (ukf) has
// fitness modes like the EKF models; its tracks need ground truth.
// Errors are one line: "FILE:LINE: what is wrong, what was expected".
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <odotune/filters/resampling.h>
#include <odotune/objectives/fitness_mode.h>
#include <odotune/objectives/rl_objective.h>
#include <odotune/objectives/rl_search_options.h>
#include <odotune/objectives/tuned_model.h>
#include <odotune/tuner/solver_choice.h>

namespace odotune::formats {

// The fixed parts of the calibrator models (not tuned; calibration_tune_job.h).
struct ExperimentCalibration {
  filters::Resampler resampler = filters::Resampler::systematic;
  filters::ResamplePolicy policy = filters::ResamplePolicy::neff;
  int particles = 0;  // 0 = the paper's count
  std::uint64_t seed = 1;
  double ext_from_gt_hz = 0.0;  // 0: the tracks' v_ext/w_ext
};

// robot_localization's EKF or UKF (models rl-ekf, rl-ukf; odotune/objectives/rl_objective.h): how its
// bags are read and tuned. Its runs are scored by the GPS-outage protocol on
// the span after until_s (odotune/jobs/rl_job.h), which the tune never sees.
struct ExperimentRl {
  std::filesystem::path params;  // resolved
  std::string node_name;         // the EKF's section of the file when it has several
  std::vector<std::string> tf;
  std::string gps_topic;
  std::filesystem::path navsat_params;  // resolved; empty: none (navsat's keys in params, if any)
  std::vector<std::string> remap;       // FROM=TO, as --remap
  double gps_heading_fit_s = 0.0;
  double until_s = 0.0;
  std::optional<double> end_s;
  std::vector<objectives::RlFitness> fitness{objectives::RlFitness::both};
  objectives::RlNoiseSpace space = objectives::RlNoiseSpace::diagonal;
  bool input_covariances = true;
  std::vector<double> outage_s{30.0, 60.0};
  double outage_every_s = 10.0;
  objectives::RlSearchOptions search;  // grid_levels, refine_decades, profile_step_decades
};

struct Experiment {
  std::filesystem::path file;
  std::string text;  // the file verbatim (hashed into the store)
  std::string name;
  std::vector<objectives::TunedModel> models;
  std::vector<std::string> tracks;  // resolved paths, sorted within each glob
  std::vector<objectives::FitnessMode>
      modes;  // empty with rl-ekf/rl-ukf, whose fitnesses are robot_localization.fitness
  std::vector<std::uint64_t> seeds;
  tuner::SolverChoice solver;  // pso, or nlopt:NAME (odotune/tuner/solver_choice.h), parsed on reading
  int particles = 50, iterations = 150;
  long evaluations = 0;
  bool leave_one_out = false;
  std::filesystem::path store;
  ExperimentCalibration calibration;
  std::optional<ExperimentRl> robot_localization;  // with model rl-ekf or rl-ukf

  bool has_ekf_models() const;         // rq, alpha, gyro
  bool has_calibrator_models() const;  // pf-calib, adaptive-pf-calib
  bool has_ukf_models() const;         // ukf
  bool has_rl_models() const;          // rl-ekf, rl-ukf
};

// Throws core::Failure.
Experiment read_experiment(const std::filesystem::path& path);
// The same for an experiment's text as if read from `path` (relative paths
// in it resolve against path's folder), e.g. the text kept in a results
// store. Throws core::Failure.
Experiment parse_experiment(const std::string& text, const std::filesystem::path& path);

}  // namespace odotune::formats
