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

#include "filters/diff_drive.h"
#include "filters/ekf.h"
#include "tracks/track.h"

namespace odotune {

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
  double t0_s = 0.0;
  std::vector<filters::WheelTravel> steps;
  std::vector<double> abs_yaw_rate_rad_s;  // per step: |gyro_z|, or |odometry yaw rate| without a gyro
  std::vector<filters::Position> fixes;    // [m]
  std::vector<filters::Position> gt;       // [m]
  std::vector<double> gt_theta_rad;        // per gt sample (NaN when the track has none)
  std::vector<ReplayRow> rows;             // rows after the start row, in time order
};

struct ReplayInputOptions {
  // Wheel base for tracks whose odometry is body velocities and whose
  // metadata gives no robot.wheel_base: only splits (v, w) into wheel travel
  // for the alpha/gyro noise models, it does not change the dead reckoning.
  double default_wheel_base_m = 0.3;
};

// Throws std::invalid_argument with one line naming the track and the problem
// when the track cannot be replayed (no odometry, no ground truth, missing
// robot metadata).
ReplayInput build_replay_input(const Track& track, const ReplayInputOptions& options = {});

}  // namespace odotune
