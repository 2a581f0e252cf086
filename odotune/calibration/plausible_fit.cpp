#include <odotune/calibration/plausible_fit.h>

#include <array>
#include <cmath>
#include <utility>

#include <fmt/format.h>

namespace odotune::calibration {

namespace {

// One value against its nominal: nullopt when within the factor.
std::optional<std::string> implausible(const char* name, double fitted, double nominal, const char* unit) {
  const double ratio = fitted / nominal;
  if (std::isfinite(ratio) && ratio >= 1.0 / kPlausibleFactor && ratio <= kPlausibleFactor) return std::nullopt;
  return fmt::format("{} = {:.4g}{} is {:.3g} × the nominal {:.4g}{} (expected {:.2g}–{:.2g} ×)", name, fitted,
                     unit, ratio, nominal, unit, 1.0 / kPlausibleFactor, kPlausibleFactor);
}

}  // namespace

std::optional<std::string> implausible_geometry(const filters::OdometryParams& fitted,
                                                const filters::OdometryParams& nominal) {
  const std::array values{
      std::pair{"wheel_radius_left_m", std::pair{fitted.wheel_radius_left_m, nominal.wheel_radius_left_m}},
      std::pair{"wheel_radius_right_m", std::pair{fitted.wheel_radius_right_m, nominal.wheel_radius_right_m}},
      std::pair{"wheel_base_m", std::pair{fitted.wheel_base_m, nominal.wheel_base_m}}};
  for (const auto& [name, v] : values)
    if (auto why = implausible(name, v.first, v.second, " m")) return why;
  return std::nullopt;
}

std::optional<std::string> implausible_twist(const filters::TwistCorrection& fitted) {
  if (auto why = implausible("scale_v", fitted.scale_v, 1.0, "")) return why;
  return implausible("scale_w", fitted.scale_w, 1.0, "");
}

std::string implausible_fit_message(const std::string& why) {
  return fmt::format(
      "calibrate: the fit is not one this robot can have: {}; its references do not determine the "
      "odometry's scale (too few, too noisy or too short fixes), and nothing was written: fit on more or more "
      "precise fixes, or correct the track's nominal values if they are this far off",
      why);
}

}  // namespace odotune::calibration
