// What one tuning run (`tune --model`, an experiment's `models:` entry, a
// stored run's `model`) tunes: the noise of one of the EKF models, or the
// settings of one of the particle-filter calibrators (issue 5, item 7;
// objectives/calibration_objective.h).
//
//   rq | alpha | gyro       EKF noise model (filters/ekf_noise.h)
//   pf-calib                plain PF calibrator's settings
//   adaptive-pf-calib       adaptive PF calibrator's settings
//
// Shared by `tune`, `grid` (experiment_yaml.h) and the commands that read a
// store (report, export), so the names are spelt in one place.
#pragma once

#include <string>
#include <string_view>

#include "filters/ekf_noise.h"

namespace odotune::cli {

enum class CalibratorModel { pf, adaptive_pf };

struct TunedModel {
  bool calibrator = false;                         // false: an EKF noise model
  filters::NoiseModel noise = filters::NoiseModel::rq;  // when !calibrator
  CalibratorModel calib = CalibratorModel::pf;     // when calibrator

  static TunedModel ekf(filters::NoiseModel m) { return {false, m, CalibratorModel::pf}; }
  static TunedModel calibration(CalibratorModel c) { return {true, filters::NoiseModel::rq, c}; }
  bool operator==(const TunedModel& o) const {
    return calibrator == o.calibrator && (calibrator ? calib == o.calib : noise == o.noise);
  }
};

// "rq", "alpha", "gyro", "pf-calib", "adaptive-pf-calib".
std::string to_string(const TunedModel& m);
// Parses the names above; false (and *out untouched) for anything else.
bool parse_tuned_model(std::string_view text, TunedModel* out);
// True for "pf-calib" and "adaptive-pf-calib" (e.g. a stored run's model).
bool is_calibrator_model_name(std::string_view text);
// "rq, alpha, gyro, pf-calib or adaptive-pf-calib", for error messages.
const char* tuned_model_names();

}  // namespace odotune::cli
