// A track (docs/track-format.md) as a recording robot_localization's node
// can replay (odotune/rlnode/sample_recording.h), and the filter's path scored
// against the track's ground truth.
//
// What the node is given, as a team's drivers would publish it:
//   odometry  the track's odometry input (odotune/tracks/odometry_input.h): encoder
//             travel through the nominal geometry, differenced per sample (as
//             a drive controller publishes it), or the measured twist or the
//             commands as they stand; with a diagonal twist covariance;
//   gyro      gyro_z, where the file fuses a yaw rate;
//   fixes     aps_x, aps_y with aps_var_x, aps_var_y (or --fix-sigma-m²).
// The filter starts at the first fix (initial_state: its x, y, and the
// heading that aligns the dead-reckoned odometry with the first fixes,
// odotune/objectives/replay_input.h's fit), since a track's ground truth is in a
// world frame, not in one that starts at the robot. The clock is the track's t.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <odotune/filters/odometry_params.h>
#include <odotune/objectives/rl_objective.h>
#include <odotune/rlnode/params.h>
#include <odotune/rlnode/recording.h>
#include <odotune/rlnode/replay.h>
#include <odotune/tracks/odometry_input.h>
#include <odotune/tracks/track.h>

namespace odotune::objectives {

struct RlTrackOptions {
  std::optional<tracks::OdometryInput> odometry;  // nullopt: the track's own (track_odometry_input)
  // The odometry twist's covariance diagonal [(m/s)², (rad/s)²]: Clearpath's
  // diff_drive_controller setting (twist_covariance_diagonal [0.001, 0.001,
  // 0.001, 1e6, 1e6, 0.03], ../shared/data/real/robot_localization_configs
  // ridgeback and warthog control.yaml).
  double odometry_var_vx = 0.001, odometry_var_vyaw = 0.03;
  // The gyro's: the phidgets_spatial driver's default angular_velocity_stdev
  // (0.02 °/s), squared.
  double gyro_var = 1.2184696791468346e-07;
  // σ [m] of fixes whose track gives no aps_var_x/aps_var_y (nullopt: such a
  // track is refused).
  std::optional<double> fix_sigma_m;
  double heading_window_s = 60.0;  // the initial heading's fit: at most this long
  // A calibration of the odometry (calibrate --config-out), applied before the
  // node sees it: wheel radii and base written into the track's geometry, or
  // a body velocity's scales and delay (v = scale_v · v_in(t − delay), the
  // message stamped `delay_s` later). At most one; it must match the input.
  std::optional<filters::OdometryParams> wheels;
  std::optional<filters::TwistCorrection> twist;

  bool IsValid(std::string* why) const;
};

struct TruthSample {
  std::int64_t t_ns = 0;
  double x = 0.0, y = 0.0;  // [m], the track's frame
};

struct RlTrack {
  std::filesystem::path file;
  rlnode::Recording rec;
  std::vector<TruthSample> truth;  // empty without gt_x, gt_y
  tracks::OdometryInput odometry = tracks::OdometryInput::wheels;
  std::string start_note;                  // where the filter starts and how its heading was found
  double initial_heading_error_rad = 0.0;  // against gt_theta at the first fix (NaN without it)
};

// Throws std::invalid_argument with one line naming the track (and the
// file's input): invalid options, a track without the odometry input or
// without what the file fuses (rlnode::load_sample_recording), fixes without
// variances and no fix_sigma_m, fewer than two fixes.
RlTrack load_rl_track(const tracks::Track& track, const std::filesystem::path& file,
                      const rlnode::RlParams& params, const RlTrackOptions& options);

// The horizontal error of the filter's position against the ground truth,
// linearly interpolated at each trajectory point in [from_ns, until_ns)
// (points more than 0.5 s from a ground-truth sample are left out).
struct TruthScore {
  double rmse_m = 0.0, mae_m = 0.0, max_m = 0.0;
  long samples = 0;
  bool finite = true;
};
TruthScore truth_score(std::span<const TruthSample> truth, std::span<const rlnode::TrajectoryPoint> trajectory,
                       std::int64_t from_ns = std::numeric_limits<std::int64_t>::min(),
                       std::int64_t until_ns = std::numeric_limits<std::int64_t>::max());
// Scores of several runs as one (RMSE over all their samples).
TruthScore pooled(std::span<const TruthScore> scores);

// The filter on one track, against its ground truth:
//   run      every fix fused, over the whole track;
//   outages  the tune's outage windows (`options`' lengths, stride and
//            warm-up), each its own run with the fixes fused before it, the
//            error over the window;
// and, against the fixes (what a user without ground truth sees), the
// tune's held-out folds and outage windows.
struct RlTrackScores {
  TruthScore run, outages;
  FixScore heldout_fixes, outage_fixes;
  std::size_t windows = 0;
  long processed = 0, rejected = 0;
  std::vector<rlnode::TrajectoryPoint> trajectory;  // the run's, with `keep_trajectory`
};
RlTrackScores score_rl_track(const RlTrack& track, const rlnode::ReplaySettings& settings,
                             const RlTuneOptions& options, bool keep_trajectory = false);

}  // namespace odotune::objectives
