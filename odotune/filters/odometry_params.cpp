#include <odotune/filters/odometry_params.h>

#include <cmath>
#include <sstream>

#include <odotune/core/why.h>

namespace odotune::filters {
namespace {

// "name = value must be a finite number > 0" when value is not; true otherwise.
bool check_positive(const char* name, double value, std::string* why) {
  if (std::isfinite(value) && value > 0.0) return true;
  std::ostringstream os;
  os << name << " = " << value << " must be a finite number > 0";
  return core::invalid(why, os.str());
}

}  // namespace

bool OdometryParams::IsValid(std::string* why) const {
  return check_positive("wheel_radius_left_m", wheel_radius_left_m, why) &&
         check_positive("wheel_radius_right_m", wheel_radius_right_m, why) &&
         check_positive("wheel_base_m", wheel_base_m, why);
}

bool TwistCorrection::IsValid(std::string* why) const {
  if (!check_positive("scale_v", scale_v, why) || !check_positive("scale_w", scale_w, why)) return false;
  if (!(std::isfinite(delay_s) && delay_s >= 0.0)) {
    std::ostringstream os;
    os << "delay_s = " << delay_s << " must be a finite number >= 0 [s]";
    return core::invalid(why, os.str());
  }
  return true;
}

}  // namespace odotune::filters
