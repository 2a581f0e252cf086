// The online pose-domain calibration (odotune/filters/pose_calibrator.h) run over a
// calibration input: its odometry rows' encoder intervals, each split at the
// position fixes stamped inside it, become the filter's samples, and each
// track starts at its known pose or from its fixes.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <odotune/calibration/calibration_input.h>
#include <odotune/filters/pose_calibrator.h>

namespace odotune::calibration {

// How each track's pose starts: acquired from the fixes (nothing assumed),
// or known (the track's first ground-truth pose, e.g. a docking station).
enum class OnlinePoseStart { fixes, known };
inline constexpr std::array<OnlinePoseStart, 2> kAllOnlinePoseStarts = {OnlinePoseStart::fixes,
                                                                        OnlinePoseStart::known};
// "fixes", "known".
std::string_view to_string(OnlinePoseStart s);
bool parse_online_pose_start(std::string_view text, OnlinePoseStart* out);

struct OnlinePoseOptions {
  // The filter; its `initial` geometry is the robot's nominal one (the
  // calibrate job sets it from the tracks).
  filters::PoseCalibratorParams filter;
  OnlinePoseStart start = OnlinePoseStart::fixes;
  double known_start_sd_xy_m = 0.01;       // sd of a known start's position [m]
  double known_start_sd_theta_rad = 0.01;  // ... and heading [rad]
  // The fixes' sd [m] where a track gives no aps_var_x/aps_var_y; without
  // it such a fix is refused (its weight would be a guess).
  std::optional<double> fix_sd_m;
  // The memory's minimum (filter.memory.min_memory_m, the fast twin's) when
  // not given: at least fix_sd_memory_factor × the fixes' median sd, so that
  // over the fast twin's memory a 1 % geometry change moves the dead
  // reckoning by about one fix sd (GPS-grade fixes need a longer memory than
  // motion capture, or the pair chases their noise).
  std::optional<double> min_memory_m;
  double fix_sd_memory_factor = 100.0;

  // True when usable; otherwise *why names the first bad value ("filter."
  // prefixed for the filter's).
  bool IsValid(std::string* why) const;
};

// One track's samples: samples[i] ends at t_s[i] (on the track's clock);
// start_pose is set for a known start.
struct OnlinePoseTrack {
  std::vector<filters::PoseCalibSample> samples;
  std::vector<double> t_s;
  std::optional<filters::PlanarPose> start_pose;
};

// Row r's interval (t[r−1], t[r]] turns the wheels by ω·Δt; a fix stamped
// inside it (or at t[r]) ends a sample there, with the wheel angles split in
// proportion to time (constant rates within an interval). A fix at the first
// row is applied before any motion. Throws std::invalid_argument naming the
// track when it has no fix, a fix has no variance and options.fix_sd_m is
// not set, or a known start finds no ground-truth pose.
OnlinePoseTrack online_pose_track(const CalibrationInput& in, const OnlinePoseOptions& options);

// The filter's memory for these tracks: options.min_memory_m when given,
// else the larger of filter.memory.min_memory_m and fix_sd_memory_factor ×
// the median fix sd (the tracks' own variances or fix_sd_m); the maximum
// is raised to the minimum when below it.
filters::DistanceMemoryParams online_pose_memory(const std::vector<const CalibrationInput*>& inputs,
                                                 const OnlinePoseOptions& options);

}  // namespace odotune::calibration
