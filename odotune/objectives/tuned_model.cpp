#include <odotune/objectives/tuned_model.h>

#include <odotune/core/enum_names.h>

namespace odotune::objectives {

namespace {
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
      Overloaded{[](filters::NoiseModel n) { return std::string(filters::to_string(n)); },
                 [](CalibratorModel c) {
                   return std::string(c == CalibratorModel::pf ? "pf-calib" : "adaptive-pf-calib");
                 },
                 [](FusionUkfModel) { return std::string("ukf"); },
                 [](RlModel r) {
                   return std::string(r.filter == filters::rl::RlFilterType::ekf ? "rl-ekf" : "rl-ukf");
                 }},
      m.kind);
}

bool parse_tuned_model(std::string_view text, TunedModel* out) {
  return core::parse_by_name(text, kAllTunedModels, out);
}

std::string tuned_model_names() { return core::names_or(kAllTunedModels); }

}  // namespace odotune::objectives
