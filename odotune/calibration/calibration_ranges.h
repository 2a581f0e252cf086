// The default initial ranges of the calibrators for a robot: its nominal
// radii ±5 % and wheel base ±15 %. For the paper's wheelchair (R = 0.32 m,
// D = 0.65 m; Fariña et al., RA-L 2026, §III) that is [0.304, 0.336] m and
// [0.5525, 0.7475] m, the paper's [0.305, 0.335] m and [0.55, 0.75] m to
// within 2.5 mm; a robot with 5 cm wheels gets ranges of its own size. One
// place for `odotune calibrate` and the calibrator tunes, so tuned settings
// carry over to the command.
#pragma once

#include <odotune/filters/odometry_params.h>
#include <odotune/filters/pf_calibrator.h>

namespace odotune::calibration {

struct CalibrationRanges {
  filters::PfCalibratorParams::Range wheel_radius_left_m, wheel_radius_right_m, wheel_base_m;
};

inline CalibrationRanges default_calibration_ranges(const filters::OdometryParams& nominal) {
  constexpr double kRadiusFraction = 0.05, kWheelBaseFraction = 0.15;
  const auto around = [](double v, double f) {
    return filters::PfCalibratorParams::Range{v * (1.0 - f), v * (1.0 + f)};
  };
  return {around(nominal.wheel_radius_left_m, kRadiusFraction),
          around(nominal.wheel_radius_right_m, kRadiusFraction),
          around(nominal.wheel_base_m, kWheelBaseFraction)};
}

}  // namespace odotune::calibration
