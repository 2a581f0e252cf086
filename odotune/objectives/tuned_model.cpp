#include <odotune/objectives/tuned_model.h>

namespace odotune::objectives {

namespace {
constexpr std::string_view kPf = "pf-calib";
constexpr std::string_view kAdaptivePf = "adaptive-pf-calib";
constexpr std::string_view kUkf = "ukf";
constexpr std::string_view kRlEkf = "rl-ekf";
constexpr std::string_view kRlUkf = "rl-ukf";

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
// Needed by clang 14 (clang-tidy parses with it), which lacks C++20's
// deduction for aggregates; GCC deduces the same without it.
template <class... F>
Overloaded(F...) -> Overloaded<F...>;
}  // namespace

std::string to_string(const TunedModel& m) {
  return std::visit(
      Overloaded{
          [](filters::NoiseModel n) { return std::string(filters::to_string(n)); },
          [](CalibratorModel c) { return std::string(c == CalibratorModel::pf ? kPf : kAdaptivePf); },
          [](FusionUkfModel) { return std::string(kUkf); },
          [](RlModel r) { return std::string(r.filter == filters::rl::RlFilterType::ekf ? kRlEkf : kRlUkf); }},
      m.kind);
}

bool parse_tuned_model(std::string_view text, TunedModel* out) {
  if (text == kUkf) {
    *out = TunedModel::fusion_ukf();
  } else if (text == kRlEkf) {
    *out = TunedModel::rl(filters::rl::RlFilterType::ekf);
  } else if (text == kRlUkf) {
    *out = TunedModel::rl(filters::rl::RlFilterType::ukf);
  } else if (text == kPf) {
    *out = TunedModel::calibration(CalibratorModel::pf);
  } else if (text == kAdaptivePf) {
    *out = TunedModel::calibration(CalibratorModel::adaptive_pf);
  } else {
    filters::NoiseModel m;
    if (!filters::parse_noise_model(text, &m)) return false;
    *out = TunedModel::ekf(m);
  }
  return true;
}

bool is_calibrator_model_name(std::string_view text) { return text == kPf || text == kAdaptivePf; }

bool is_ukf_model_name(std::string_view text) { return text == kUkf; }

bool is_rl_model_name(std::string_view text) { return text == kRlEkf || text == kRlUkf; }

const char* tuned_model_names() {
  return "rq, alpha, gyro, pf-calib, adaptive-pf-calib, ukf, rl-ekf or rl-ukf";
}

}  // namespace odotune::objectives
