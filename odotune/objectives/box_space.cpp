#include <odotune/objectives/box_space.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace odotune::objectives {

BoxSpace::BoxSpace(std::vector<ParamSpec> params) : params_(std::move(params)) {
  for (const auto& p : params_) {
    if (!std::isfinite(p.lower) || !std::isfinite(p.upper) || !(p.lower < p.upper) ||
        (p.log_scale && !(p.lower > 0.0)))
      throw std::invalid_argument("parameter " + p.name +
                                  ": bounds must be finite with lower < upper (and > 0 when "
                                  "searched in log scale)");
    box_lo_.push_back(p.log_scale ? std::log10(p.lower) : p.lower);
    box_hi_.push_back(p.log_scale ? std::log10(p.upper) : p.upper);
  }
}

std::size_t BoxSpace::index_of(std::string_view name) const {
  std::size_t i = 0;
  while (i < params_.size() && params_[i].name != name) ++i;
  return i;
}

std::string BoxSpace::names() const {
  std::string out;
  for (const auto& p : params_) out += (out.empty() ? "" : ", ") + p.name;
  return out;
}

std::vector<double> BoxSpace::to_physical(std::span<const double> box_x) const {
  if (box_x.size() != params_.size()) throw std::invalid_argument("BoxSpace: wrong dimension");
  std::vector<double> out(params_.size());
  for (std::size_t i = 0; i < params_.size(); ++i) {
    const double b = std::clamp(box_x[i], box_lo_[i], box_hi_[i]);
    out[i] = params_[i].log_scale ? std::pow(10.0, b) : b;
  }
  return out;
}

std::vector<double> BoxSpace::to_box(std::span<const double> physical) const {
  if (physical.size() != params_.size()) throw std::invalid_argument("BoxSpace: wrong dimension");
  std::vector<double> out(params_.size());
  for (std::size_t i = 0; i < params_.size(); ++i)
    out[i] = params_[i].log_scale ? std::log10(physical[i]) : physical[i];
  return out;
}

}  // namespace odotune::objectives
