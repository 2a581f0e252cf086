// Experiment files for `odotune grid` (see experiments/*.yaml, commented):
//
//   format: odotune-experiment/1
//   name: study
//   models: [rq, alpha, gyro]            # also pf-calib, adaptive-pf-calib, ukf (objectives/tuned_model.h)
//   tracks: [../data/tracks/track*.csv]   # paths or globs, relative to this file
//   modes: [1, 2, 3, 4, 5, 6, 7]
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
// A calibrator model (pf-calib, adaptive-pf-calib) has no fitness mode: its
// cells are made for the first listed mode only (the run records that mode),
// so a calibrator run is not repeated per mode. The fusion UKF (ukf) has
// fitness modes like the EKF models; its tracks need ground truth.
// Errors are one line: "FILE:LINE: what is wrong, what was expected".
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "filters/resampling.h"
#include "objectives/tuned_model.h"

namespace odotune {

// The fixed parts of the calibrator models (not tuned; calibration_tune_job.h).
struct ExperimentCalibration {
  filters::Resampler resampler = filters::Resampler::systematic;
  filters::ResamplePolicy policy = filters::ResamplePolicy::neff;
  int particles = 0;  // 0 = the paper's count
  std::uint64_t seed = 1;
  double ext_from_gt_hz = 0.0;  // 0: the tracks' v_ext/w_ext
};

struct Experiment {
  std::filesystem::path file;
  std::string text;  // the file verbatim (hashed into the store)
  std::string name;
  std::vector<TunedModel> models;
  std::vector<std::string> tracks;  // resolved paths, sorted within each glob
  std::vector<int> modes;
  std::vector<std::uint64_t> seeds;
  std::string solver = "pso";
  int particles = 50, iterations = 150;
  long evaluations = 0;
  bool leave_one_out = false;
  std::filesystem::path store;
  ExperimentCalibration calibration;

  bool has_ekf_models() const;         // rq, alpha, gyro
  bool has_calibrator_models() const;  // pf-calib, adaptive-pf-calib
  bool has_ukf_models() const;         // ukf
};

// Throws odotune::Failure.
Experiment read_experiment(const std::filesystem::path& path);
// The same for an experiment's text as if read from `path` (relative paths
// in it resolve against path's folder), e.g. the text kept in a results
// store. Throws odotune::Failure.
Experiment parse_experiment(const std::string& text, const std::filesystem::path& path);

}  // namespace odotune
