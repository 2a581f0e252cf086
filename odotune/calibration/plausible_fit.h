// Whether a fitted odometry calibration is one a robot can have. A real
// robot's wheels and base differ from their nominal values by a few per cent
// (OptiOdom's base by 1 %, Lost in the Woods' scale by 5 %, MRCLAM's turn by
// 5-14 %: docs/diagnosis/README.md), and a drive's speed scale likewise. A fit
// that moves a value by a factor of 2 or more has not been determined by its
// references: pose-domain fits to few or noisy position fixes shrink the
// whole path towards a point (radii and base scaled down together), which
// lowers the cost without being the robot (docs/robot-localization.md,
// "Calibrate, then tune").
#pragma once

#include <optional>
#include <string>

#include <odotune/filters/odometry_params.h>

namespace odotune::calibration {

// A fitted value is plausible within [1/kPlausibleFactor, kPlausibleFactor]
// times its nominal value (a scale: times 1).
inline constexpr double kPlausibleFactor = 2.0;

// nullopt when every fitted value is plausible against the nominal one;
// otherwise one sentence naming the first that is not, e.g. "wheel_radius_left_m
// = 0.005 m is 0.122 × the nominal 0.041 m (expected 0.5–2 ×)".
std::optional<std::string> implausible_geometry(const filters::OdometryParams& fitted,
                                                const filters::OdometryParams& nominal);
std::optional<std::string> implausible_twist(const filters::TwistCorrection& fitted);

// The one line `calibrate` refuses such a fit with (nothing written), `why`
// being one of the sentences above.
std::string implausible_fit_message(const std::string& why);

}  // namespace odotune::calibration
