#include "filters/odometry_params.h"

#include <sstream>

namespace odotune::filters {
namespace {

// "name = value must be a finite number > 0" when value is not; true otherwise.
bool check_positive(const char* name, double value, std::string* why) {
  if (std::isfinite(value) && value > 0.0) return true;
  if (why) {
    std::ostringstream os;
    os << name << " = " << value << " must be a finite number > 0";
    *why = os.str();
  }
  return false;
}

}  // namespace

bool OdometryParams::IsValid(std::string* why) const {
  return check_positive("wheel_radius_left_m", wheel_radius_left_m, why) &&
         check_positive("wheel_radius_right_m", wheel_radius_right_m, why) &&
         check_positive("wheel_base_m", wheel_base_m, why);
}

}  // namespace odotune::filters
