// What a filter replay needs from a track, laid out for the replay loop:
// wheel-travel steps, position fixes and ground-truth samples in time order.
//
// Row semantics (shared by the step and the fast replay): rows are taken in
// time order from the first row that has a ground-truth pose (the filter starts
// there, at that pose). At each later row the filter first predicts with the
// odometry increment ending at that row (if any), then corrects with the
// row's position fix (if any), and then its position is compared with the
// row's ground truth (if any).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <odotune/filters/diff_drive.h>
#include <odotune/filters/ekf.h>
#include <odotune/tracks/track.h>

namespace odotune::objectives {

enum class OdometrySource { ticks, wheel_rates, commands };
std::string_view to_string(OdometrySource s);

struct ReplayRow {
  double t_s = 0.0;
  std::int32_t step = -1;  // index into steps, or -1
  std::int32_t fix = -1;   // index into fixes, or -1
  std::int32_t gt = -1;    // index into gt, or -1
};

struct ReplayInput {
  std::string track_name;
  OdometrySource source = OdometrySource::ticks;
  double wheel_base_m = 0.0;
  filters::Pose initial_pose = filters::Pose::Zero();
  // Its covariance: the EKF's default (1 cm, 1°) at a ground-truth start;
  // at the first fix, the fix's variance and (10°)² for the fitted heading.
  filters::StateCov initial_cov = filters::EkfParams{}.initial_cov;
  double t0_s = 0.0;
  std::vector<filters::WheelTravel> steps;
  std::vector<double> abs_yaw_rate_rad_s;  // per step: |gyro_z|, or |odometry yaw rate| without a gyro
  std::vector<filters::Position> fixes;    // [m]
  // Per fix: its own variances [m²] from the track's aps_var_x/aps_var_y, NaN
  // where the track gives none (the noise model's Q is used there).
  std::vector<double> fix_var_x_m2, fix_var_y_m2;
  // The reference the replay starts from and is scored against (options).
  bool reference_is_fixes = false;
  std::string initial_pose_note;      // how the initial pose was found (fixes reference)
  std::vector<filters::Position> gt;  // [m]
  std::vector<double> gt_theta_rad;   // per gt sample (NaN when the track has none)
  std::vector<ReplayRow> rows;        // rows after the start row, in time order
};

// What a replay starts from:
//   ground_truth: the first row with a ground-truth pose (the study's setup;
//     a track without ground truth is refused);
//   fixes: the first position fix, with the heading that best aligns the
//     dead-reckoned odometry with the fixes of the first `heading_window_s`
//     (a least-squares rotation of the path about the start, Umeyama's
//     closed form without scale: θ₀ = atan2(Σ o×f, Σ o·f) over the pairs of
//     odometry path point o and fix f, both relative to the start), for
//     tracks whose only reference is the fixes; ground truth, when present,
//     is still kept for scoring.
enum class ReplayReference { ground_truth, fixes };

struct ReplayInputOptions {
  ReplayReference reference = ReplayReference::ground_truth;
  double heading_window_s = 60.0;  // fixes reference: the window of the heading fit
  // Wheel base for tracks whose odometry is body velocities and whose
  // metadata gives no robot.wheel_base: only splits (v, w) into wheel travel
  // for the alpha/gyro noise models, it does not change the dead reckoning.
  double default_wheel_base_m = 0.3;
};

// Throws std::invalid_argument with one line naming the track and the problem
// when the track cannot be replayed (no odometry, no ground truth, missing
// robot metadata).
ReplayInput build_replay_input(const tracks::Track& track, const ReplayInputOptions& options = {});

// The replay input a track supports: from ground truth when it has it, else
// from its first fix (ReplayReference::fixes). For exports and figures that
// need the odometry and a start, not ground-truth metrics.
ReplayInput build_replay_input_any(const tracks::Track& track);

}  // namespace odotune::objectives
