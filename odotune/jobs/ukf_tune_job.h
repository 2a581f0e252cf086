// One tuning run of the velocity-fusion UKF's noise:
// tracks × fitness mode × solver × seed → the tuned process-noise rates,
// static odometry variances, gyro variance and external-variance scale
// (odotune/learned/ukf_objective.h), scored against the default settings. The
// mirror of tune_job.h for the UKF; computation only (the commands parse and
// print), so `tune` and `grid` share it.
//
// Baseline: UkfSettings{} (q_v 0.05 (m/s)²/s, q_w 0.1 (rad/s)²/s, odometry
// variances 1e-3, gyro variance 4e-6 (rad/s)², the tracks' own external
// variances). Tuned: the solver's best point — or the default point when it
// scores better (PSO never evaluates the default itself), so the tuned
// fitness is never worse than the baseline's on the tuning tracks;
// `default_kept` says when that happened. NLopt starts from the default
// point. Metrics: the fused pose's position errors against the ground truth
// (ukf_fusion.h), per track and their means.
#pragma once

#include <string>
#include <vector>

#include <odotune/jobs/tune_job.h>
#include <odotune/learned/fusion_input.h>
#include <odotune/learned/ukf_objective.h>
#include <odotune/objectives/metrics.h>
#include <odotune/tuner/summary.h>

namespace odotune::jobs {

struct UkfTuneRequest : SolverSettings {
  objectives::FitnessMode mode = objectives::kDefaultFitnessMode;  // against ground truth (1..7)
  bool IsValid(std::string* why) const;
};

struct UkfTuneOutcome {
  UkfTuneRequest request;
  std::vector<std::string> param_names;  // ukf_space() order
  std::vector<std::string> param_units;
  std::vector<double> default_params;  // physical, in param_units
  std::vector<double> params;          // tuned, physical
  learned::UkfSettings default_settings, tuned_settings;
  double baseline_fitness = 0.0, tuned_fitness = 0.0;  // the objective's, lower is better
  bool default_kept = false;
  std::vector<TrackScore> tracks;                      // per track: default vs tuned position errors
  objectives::ErrorMetrics baseline_mean, tuned_mean;  // means over tracks
  long failures = 0;                                   // evaluations that scored the divergence penalty
  tuner::Summary summary;
};

// The fusion input `tune` and `grid` use for a track (10 Hz, the paper's
// rate). Throws std::invalid_argument with one line naming the track when it
// cannot be fused or has no ground truth to score against.
learned::FusionInput ukf_fusion_input(const tracks::Track& track);

// Position errors of `settings` on each input (the metrics are the
// divergence penalty for a run whose filter turned unhealthy).
std::vector<objectives::ErrorMetrics> ukf_track_errors(const std::vector<const learned::FusionInput*>& inputs,
                                                       const learned::UkfSettings& settings);

// Runs the solver; throws std::invalid_argument for an invalid request or no
// tracks (or a track without ground truth) and std::runtime_error when the
// solver fails.
UkfTuneOutcome run_ukf_tune(const std::vector<const learned::FusionInput*>& inputs,
                            const UkfTuneRequest& request);

}  // namespace odotune::jobs
