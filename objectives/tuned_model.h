// What one tuning run (`tune --model`, an experiment's `models:` entry, a
// stored run's `model`) tunes: the noise of one of the EKF models, the
// settings of one of the particle-filter calibrators (issue 5, item 7;
// objectives/calibration_objective.h), or the noise of the velocity-fusion
// UKF (issue 6, item 1; objectives/ukf_objective.h).
//
//   rq | alpha | gyro       EKF noise model (filters/ekf_noise.h)
//   pf-calib                plain PF calibrator's settings
//   adaptive-pf-calib       adaptive PF calibrator's settings
//   ukf                     the (V, W) fusion UKF's noise (filters/velocity_ukf.h)
//
// Shared by `tune`, `grid` (experiment_yaml.h) and the commands that read a
// store (report, export), so the names are spelt in one place.
#pragma once

#include <string>
#include <string_view>

#include "filters/ekf_noise.h"

namespace odotune {

enum class CalibratorModel { pf, adaptive_pf };

struct TunedModel {
  bool calibrator = false;                              // true: a PF calibrator
  filters::NoiseModel noise = filters::NoiseModel::rq;  // when an EKF model
  CalibratorModel calib = CalibratorModel::pf;          // when calibrator
  bool ukf = false;                                     // true: the fusion UKF (calibrator false)

  static TunedModel ekf(filters::NoiseModel m) { return {false, m, CalibratorModel::pf, false}; }
  static TunedModel calibration(CalibratorModel c) { return {true, filters::NoiseModel::rq, c, false}; }
  static TunedModel fusion_ukf() { return {false, filters::NoiseModel::rq, CalibratorModel::pf, true}; }
  // An EKF noise model (rq, alpha, gyro): neither a calibrator nor the UKF.
  bool is_ekf() const { return !calibrator && !ukf; }
  bool operator==(const TunedModel& o) const {
    if (calibrator != o.calibrator || ukf != o.ukf) return false;
    return calibrator ? calib == o.calib : (ukf || noise == o.noise);
  }
};

// "rq", "alpha", "gyro", "pf-calib", "adaptive-pf-calib", "ukf".
std::string to_string(const TunedModel& m);
// Parses the names above; false (and *out untouched) for anything else.
bool parse_tuned_model(std::string_view text, TunedModel* out);
// True for "pf-calib" and "adaptive-pf-calib" (e.g. a stored run's model).
bool is_calibrator_model_name(std::string_view text);
// True for "ukf".
bool is_ukf_model_name(std::string_view text);
// "rq, alpha, gyro, pf-calib, adaptive-pf-calib or ukf", for error messages.
const char* tuned_model_names();

}  // namespace odotune
