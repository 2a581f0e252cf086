#include "objectives/tuned_model.h"

namespace odotune {

namespace {
constexpr std::string_view kPf = "pf-calib";
constexpr std::string_view kAdaptivePf = "adaptive-pf-calib";
constexpr std::string_view kUkf = "ukf";
}  // namespace

std::string to_string(const TunedModel& m) {
  if (m.ukf) return std::string(kUkf);
  if (!m.calibrator) return std::string(filters::to_string(m.noise));
  return std::string(m.calib == CalibratorModel::pf ? kPf : kAdaptivePf);
}

bool parse_tuned_model(std::string_view text, TunedModel* out) {
  if (text == kUkf) {
    *out = TunedModel::fusion_ukf();
    return true;
  }
  if (text == kPf) {
    *out = TunedModel::calibration(CalibratorModel::pf);
    return true;
  }
  if (text == kAdaptivePf) {
    *out = TunedModel::calibration(CalibratorModel::adaptive_pf);
    return true;
  }
  filters::NoiseModel m;
  if (!filters::parse_noise_model(text, &m)) return false;
  *out = TunedModel::ekf(m);
  return true;
}

bool is_calibrator_model_name(std::string_view text) { return text == kPf || text == kAdaptivePf; }

bool is_ukf_model_name(std::string_view text) { return text == kUkf; }

const char* tuned_model_names() { return "rq, alpha, gyro, pf-calib, adaptive-pf-calib or ukf"; }

}  // namespace odotune
