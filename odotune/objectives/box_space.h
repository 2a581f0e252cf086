// A named, bounded parameter space and its mapping to the box an optimiser
// sees: a parameter whose bounds span two or more decades is searched in
// log10 space (its box coordinate is log10(value)), others linearly. Shared
// by the EKF noise models (param_space.h) and the particle-filter calibrator's
// settings (calibration_objective.h).
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace odotune::objectives {

struct ParamSpec {
  std::string name;     // e.g. "r1_mm2"
  std::string unit;     // e.g. "mm²"
  double lower, upper;  // physical bounds, in `unit`; finite, lower < upper (> 0 if log_scale)
  bool log_scale;       // searched as log10(value)
  std::string meaning;
};

class BoxSpace {
 public:
  BoxSpace() = default;
  // Throws std::invalid_argument naming a parameter with unusable bounds.
  explicit BoxSpace(std::vector<ParamSpec> params);

  const std::vector<ParamSpec>& params() const { return params_; }
  std::size_t dim() const { return params_.size(); }
  // Index of the parameter called `name` (dim() when there is none).
  std::size_t index_of(std::string_view name) const;
  // The names, comma-separated, for "expected …" messages.
  std::string names() const;

  // The optimiser's box (log10 of the bounds for log-scaled parameters).
  std::pair<std::vector<double>, std::vector<double>> box() const { return {box_lo_, box_hi_}; }
  // Box coordinates ↔ physical values (in each ParamSpec's unit). Box
  // coordinates are clamped into the box first.
  std::vector<double> to_physical(std::span<const double> box_x) const;
  std::vector<double> to_box(std::span<const double> physical) const;

 private:
  std::vector<ParamSpec> params_;
  std::vector<double> box_lo_, box_hi_;  // computed once: to_physical runs per evaluation
};

}  // namespace odotune::objectives
