// What one tuning run (`tune --model`, an experiment's `models:` entry, a
// stored run's `model`) tunes:
//
//   rq | alpha | gyro       EKF noise model (odotune/filters/ekf_noise.h)
//   pf-calib                plain PF calibrator's settings (odotune/calibration/calibration_objective.h)
//   adaptive-pf-calib       adaptive PF calibrator's settings
//   ukf                     the (V, W) fusion UKF's noise (odotune/learned/ukf_objective.h)
//   rl-ekf | rl-ukf         robot_localization's EKF or UKF on a bag and its parameter
//                           file (odotune/objectives/rl_objective.h; grid only, `tune --rl-params` otherwise)
//
// Shared by `tune`, `grid` (experiment_yaml.h) and the commands that read a
// store (report, export), so the names are spelt in one place.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <variant>

#include <odotune/filters/ekf_noise.h>
#include <odotune/filters/rl_filter.h>

namespace odotune::objectives {

enum class CalibratorModel { pf, adaptive_pf };
struct FusionUkfModel {
  bool operator==(const FusionUkfModel&) const = default;
};
struct RlModel {
  filters::rl::RlFilterType filter = filters::rl::RlFilterType::ekf;  // ekf_node or ukf_node
  bool operator==(const RlModel&) const = default;
};

// One of the kinds above; a value can only be one of them.
struct TunedModel {
  std::variant<filters::NoiseModel, CalibratorModel, FusionUkfModel, RlModel> kind = filters::NoiseModel::rq;

  static TunedModel ekf(filters::NoiseModel m) { return {m}; }
  static TunedModel calibration(CalibratorModel c) { return {c}; }
  static TunedModel fusion_ukf() { return {FusionUkfModel{}}; }
  static TunedModel rl(filters::rl::RlFilterType f) { return {RlModel{f}}; }
  bool is_ekf() const { return std::holds_alternative<filters::NoiseModel>(kind); }  // rq, alpha, gyro
  bool is_calibrator() const { return std::holds_alternative<CalibratorModel>(kind); }
  bool is_ukf() const { return std::holds_alternative<FusionUkfModel>(kind); }
  bool is_rl() const { return std::holds_alternative<RlModel>(kind); }  // rl-ekf, rl-ukf
  // Preconditions: is_ekf(), is_calibrator(), is_rl() respectively.
  filters::NoiseModel noise() const { return std::get<filters::NoiseModel>(kind); }
  CalibratorModel calib() const { return std::get<CalibratorModel>(kind); }
  filters::rl::RlFilterType rl_filter() const { return std::get<RlModel>(kind).filter; }
  bool operator==(const TunedModel&) const = default;
};

// Every model, in the order of their names below (--model's choices).
inline constexpr std::array<TunedModel, 8> kAllTunedModels = {
    TunedModel{filters::NoiseModel::rq},
    TunedModel{filters::NoiseModel::alpha},
    TunedModel{filters::NoiseModel::gyro},
    TunedModel{CalibratorModel::pf},
    TunedModel{CalibratorModel::adaptive_pf},
    TunedModel{FusionUkfModel{}},
    TunedModel{RlModel{filters::rl::RlFilterType::ekf}},
    TunedModel{RlModel{filters::rl::RlFilterType::ukf}}};

// "rq", "alpha", "gyro", "pf-calib", "adaptive-pf-calib", "ukf", "rl-ekf", "rl-ukf".
std::string to_string(const TunedModel& m);
// Parses the names above (a stored run's model, an experiment's models:
// entry; --model is parsed by the cli from the same names); false (and
// *out untouched) for anything else.
bool parse_tuned_model(std::string_view text, TunedModel* out);
// "rq, alpha, gyro, pf-calib, adaptive-pf-calib, ukf, rl-ekf or rl-ukf", for error messages.
std::string tuned_model_names();

}  // namespace odotune::objectives
