#include "objectives/replay_input.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

namespace odotune {

std::string_view to_string(OdometrySource s) {
  switch (s) {
    case OdometrySource::ticks: return "ticks";
    case OdometrySource::wheel_rates: return "wheel_rates";
    case OdometrySource::commands: return "commands";
  }
  return "?";
}

namespace {

[[noreturn]] void fail(const Track& track, const std::string& what) {
  throw std::invalid_argument(fmt::format("track '{}': {}", track.name(), what));
}

double require(const Track& track, const std::optional<double>& v, const char* key) {
  if (!v) fail(track, fmt::format("metadata '{}' is needed for its wheel odometry", key));
  return *v;
}

}  // namespace

ReplayInput build_replay_input(const Track& track, const ReplayInputOptions& options) {
  using filters::Position;
  using filters::WheelTravel;
  ReplayInput in;
  in.track_name = track.name();
  if (!track.has_odometry()) fail(track, "no odometry columns (ticks_*, omega_* or v_cmd/w_cmd)");
  if (!track.has_gt()) fail(track, "no ground truth (gt_x, gt_y): metrics need it");

  const auto& meta = track.meta();
  double Rl = 0.0, Rr = 0.0, tick_rev = 0.0;
  if (track.has_ticks() || track.has_wheel_rates()) {
    in.source = track.has_ticks() ? OdometrySource::ticks : OdometrySource::wheel_rates;
    Rl = require(track, meta.wheel_radius_left_m, "robot.wheel_radius_left");
    Rr = require(track, meta.wheel_radius_right_m, "robot.wheel_radius_right");
    in.wheel_base_m = require(track, meta.wheel_base_m, "robot.wheel_base");
    if (in.source == OdometrySource::ticks)
      tick_rev = require(track, meta.ticks_per_rev, "robot.ticks_per_rev");
  } else {
    in.source = OdometrySource::commands;
    in.wheel_base_m = meta.wheel_base_m.value_or(options.default_wheel_base_m);
  }

  const std::size_t n = track.size();
  const auto& t = track.t();
  const auto& gx = track.col(Col::gt_x);
  const auto& gy = track.col(Col::gt_y);
  std::size_t start = 0;
  while (start < n && (std::isnan(gx[start]) || std::isnan(gy[start]))) ++start;
  if (start == n) fail(track, "no row with a ground-truth position");
  in.t0_s = t[start];
  const bool has_theta = track.has(Col::gt_theta);
  if (has_theta && std::isnan(track.col(Col::gt_theta)[start]))
    fail(track, fmt::format("the first ground-truth row (t = {} s) has no gt_theta", t[start]));
  in.initial_pose << gx[start], gy[start], has_theta ? track.col(Col::gt_theta)[start] : 0.0;

  // Odometry sample presence at row i.
  auto odo_at = [&](std::size_t i) {
    switch (in.source) {
      case OdometrySource::ticks: return track.ticks_l()[i] != kNoTick && track.ticks_r()[i] != kNoTick;
      case OdometrySource::wheel_rates: return track.at(Col::omega_l, i) && track.at(Col::omega_r, i);
      case OdometrySource::commands: return track.at(Col::v_cmd, i) && track.at(Col::w_cmd, i);
    }
    return false;
  };
  const bool has_gyro = track.has(Col::gyro_z);
  const double two_pi = 2.0 * std::numbers::pi;

  // The last odometry sample at or before the start row.
  std::ptrdiff_t last_odo = -1;
  for (std::size_t i = 0; i <= start; ++i)
    if (odo_at(i)) last_odo = static_cast<std::ptrdiff_t>(i);
  double last_gyro = std::nan("");
  for (std::size_t i = 0; i <= start; ++i)
    if (has_gyro && track.at(Col::gyro_z, i)) last_gyro = track.col(Col::gyro_z)[i];

  for (std::size_t i = start + 1; i < n; ++i) {
    ReplayRow row;
    row.t_s = t[i];
    if (has_gyro && track.at(Col::gyro_z, i)) last_gyro = track.col(Col::gyro_z)[i];
    if (odo_at(i)) {
      if (last_odo >= 0) {
        const auto p = static_cast<std::size_t>(last_odo);
        const double dt = t[i] - t[p];
        WheelTravel u;
        switch (in.source) {
          case OdometrySource::ticks:
            u.left_m = static_cast<double>(track.ticks_l()[i] - track.ticks_l()[p]) * two_pi * Rl / tick_rev;
            u.right_m = static_cast<double>(track.ticks_r()[i] - track.ticks_r()[p]) * two_pi * Rr / tick_rev;
            break;
          case OdometrySource::wheel_rates:  // trapezoidal rule
            u.left_m = 0.5 * (track.col(Col::omega_l)[p] + track.col(Col::omega_l)[i]) * Rl * dt;
            u.right_m = 0.5 * (track.col(Col::omega_r)[p] + track.col(Col::omega_r)[i]) * Rr * dt;
            break;
          case OdometrySource::commands: {  // zero-order hold of the previous command
            const double d = track.col(Col::v_cmd)[p] * dt;
            const double dth = track.col(Col::w_cmd)[p] * dt;
            u.left_m = d - 0.5 * dth * in.wheel_base_m;
            u.right_m = d + 0.5 * dth * in.wheel_base_m;
            break;
          }
        }
        const double yaw_rate = std::isnan(last_gyro) ? (u.right_m - u.left_m) / in.wheel_base_m / dt
                                                      : last_gyro;
        row.step = static_cast<std::int32_t>(in.steps.size());
        in.steps.push_back(u);
        in.abs_yaw_rate_rad_s.push_back(std::abs(yaw_rate));
      }
      last_odo = static_cast<std::ptrdiff_t>(i);
    }
    if (track.at(Col::aps_x, i) && track.at(Col::aps_y, i)) {
      row.fix = static_cast<std::int32_t>(in.fixes.size());
      in.fixes.emplace_back(track.col(Col::aps_x)[i], track.col(Col::aps_y)[i]);
    }
    if (!std::isnan(gx[i]) && !std::isnan(gy[i])) {
      row.gt = static_cast<std::int32_t>(in.gt.size());
      in.gt.emplace_back(gx[i], gy[i]);
      in.gt_theta_rad.push_back(has_theta ? track.col(Col::gt_theta)[i] : std::nan(""));
    }
    if (row.step >= 0 || row.fix >= 0 || row.gt >= 0) in.rows.push_back(row);
  }
  if (in.gt.empty()) fail(track, "only one ground-truth row: nothing to compare with");
  return in;
}

}  // namespace odotune
