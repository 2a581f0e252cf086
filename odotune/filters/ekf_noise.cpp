#include <odotune/filters/ekf_noise.h>

#include <cmath>
#include <string>

#include <odotune/core/enum_names.h>
#include <odotune/core/why.h>

namespace odotune::filters {

std::string_view to_string(NoiseModel m) {
  switch (m) {
    case NoiseModel::rq: return "rq";
    case NoiseModel::alpha: return "alpha";
    case NoiseModel::gyro: return "gyro";
  }
  return "?";
}

bool parse_noise_model(std::string_view text, NoiseModel* out) {
  return core::parse_by_name(text, kAllNoiseModels, out);
}

bool NoiseParams::IsValid(std::string* why) const {
  auto out_of_range = [&](const char* name, double v, const char* expected) {
    return core::invalid(why, std::string(name) + " = " + std::to_string(v) + ": expected " + expected);
  };
  const struct {
    const char* name;
    double v;
  } nonneg[] = {{"r_x_m2", r_x_m2}, {"r_y_m2", r_y_m2}, {"r_theta_rad2", r_theta_rad2}, {"a1", a1}, {"a2", a2},
                {"b1", b1},         {"b2", b2}};
  for (const auto& f : nonneg)
    if (!std::isfinite(f.v) || f.v < 0.0) return out_of_range(f.name, f.v, "a finite value >= 0");
  if (!std::isfinite(q_x_m2) || q_x_m2 <= 0.0) return out_of_range("q_x_m2", q_x_m2, "a finite value > 0");
  if (!std::isfinite(q_y_m2) || q_y_m2 <= 0.0) return out_of_range("q_y_m2", q_y_m2, "a finite value > 0");
  if (model == NoiseModel::alpha && (b1 != 0.0 || b2 != 0.0))
    return out_of_range(b1 != 0.0 ? "b1" : "b2", b1 != 0.0 ? b1 : b2, "0 for the alpha model (use gyro)");
  return true;
}

}  // namespace odotune::filters
