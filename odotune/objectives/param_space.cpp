#include <odotune/objectives/param_space.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace odotune::objectives {

using filters::NoiseModel;
using filters::NoiseParams;

namespace {
constexpr double kMm2ToM2 = 1e-6;
constexpr double kApsSigmaM = 0.060;  // the study's fix noise, σ = 60 mm (§2.1)
}  // namespace

ParamSpace ParamSpace::for_model(NoiseModel model) {
  std::vector<ParamSpec> params;
  switch (model) {
    case NoiseModel::rq:  // §2.3.1
      params = {{"r1_mm2", "mm²", 1.0, 1e5, true, "process noise of x per prediction step"},
                {"r2_mm2", "mm²", 1.0, 1e5, true, "process noise of y per prediction step"},
                {"r3_rad2", "rad²", 1e-6, 1.0, true, "process noise of θ per prediction step"},
                {"q1_mm2", "mm²", 10.0, 1e4, true, "measurement noise of a fix's x"},
                {"q2_mm2", "mm²", 10.0, 1e4, true, "measurement noise of a fix's y"}};
      break;
    case NoiseModel::alpha:  // §2.3.2
      params = {{"alpha1", "-", 0.0, 1.0, false, "wheel noise per unit of own travel"},
                {"alpha2", "-", 0.0, 1.0, false, "wheel noise per unit of travel difference"}};
      break;
    case NoiseModel::gyro:  // §2.3.3
      params = {{"a1", "-", 0.0, 1.0, false, "base of α1"},
                {"a2", "-", 0.0, 1.0, false, "base of α2"},
                {"b1", "s/rad", 0.0, 5.0, false, "growth of α1 with |ω_z|"},
                {"b2", "s/rad", 0.0, 5.0, false, "growth of α2 with |ω_z|"}};
      break;
  }
  return ParamSpace(model, std::move(params));
}

NoiseParams ParamSpace::to_noise(std::span<const double> v) const {
  if (v.size() != dim()) throw std::invalid_argument("ParamSpace: wrong dimension");
  NoiseParams n;
  n.model = model_;
  n.q_x_m2 = n.q_y_m2 = kApsSigmaM * kApsSigmaM;
  switch (model_) {
    case NoiseModel::rq:
      n.r_x_m2 = v[0] * kMm2ToM2;
      n.r_y_m2 = v[1] * kMm2ToM2;
      n.r_theta_rad2 = v[2];
      n.q_x_m2 = v[3] * kMm2ToM2;
      n.q_y_m2 = v[4] * kMm2ToM2;
      break;
    case NoiseModel::alpha:
      n.a1 = v[0];
      n.a2 = v[1];
      break;
    case NoiseModel::gyro:
      n.a1 = v[0];
      n.a2 = v[1];
      n.b1 = v[2];
      n.b2 = v[3];
      break;
  }
  return n;
}

std::vector<double> ParamSpace::from_noise(const NoiseParams& n) const {
  switch (model_) {
    case NoiseModel::rq:
      return {n.r_x_m2 / kMm2ToM2, n.r_y_m2 / kMm2ToM2, n.r_theta_rad2, n.q_x_m2 / kMm2ToM2,
              n.q_y_m2 / kMm2ToM2};
    case NoiseModel::alpha: return {n.a1, n.a2};
    case NoiseModel::gyro: return {n.a1, n.a2, n.b1, n.b2};
  }
  return {};
}

NoiseParams baseline_noise() {
  NoiseParams n;
  n.model = NoiseModel::alpha;
  n.a1 = 0.01;
  n.a2 = 0.01;
  n.q_x_m2 = n.q_y_m2 = kApsSigmaM * kApsSigmaM;
  return n;
}

}  // namespace odotune::objectives
