#include <odotune/objectives/replay_input.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/planar_motion.h>

namespace odotune::objectives {

std::string_view to_string(OdometrySource s) {
  switch (s) {
    case OdometrySource::ticks: return "ticks";
    case OdometrySource::wheel_rates: return "wheel_rates";
    case OdometrySource::commands: return "commands";
  }
  return "?";
}

namespace {

[[noreturn]] void fail_replay(const tracks::Track& track, const std::string& what) {
  throw std::invalid_argument(fmt::format("track '{}': {}", track.name(), what));
}

double require(const tracks::Track& track, const std::optional<double>& v, const char* key) {
  if (!v) fail_replay(track, fmt::format("metadata '{}' is needed for its wheel odometry", key));
  return *v;
}

// θ₀ that rotates the dead-reckoned path (started at heading 0) onto the
// fixes, both relative to the start (header, ReplayReference::fixes). The fit
// stops once the robot has driven 20 fix σ (at least 5 m), so that neither
// the fixes' noise nor the odometry's own heading drift decides it, or at
// heading_window_s.
// `fix_var_m2`: the fixes' variance per axis.
double initial_heading_from_fixes(const ReplayInput& in, double fix_var_m2, double window_s,
                                  std::string* note) {
  const double enough_m = std::max(5.0, 20.0 * std::sqrt(fix_var_m2));
  double x = 0.0, y = 0.0, th = 0.0;
  double dot = 0.0, cross = 0.0, reach = 0.0, driven = 0.0;
  long pairs = 0;
  double t_end = in.t0_s;
  for (const ReplayRow& row : in.rows) {
    if (row.step >= 0) {
      const filters::WheelTravel& u = in.steps[static_cast<std::size_t>(row.step)];
      core::midpoint_advance(&x, &y, &th, u.left_m, u.right_m, in.wheel_base_m);
      driven += std::abs(0.5 * (u.left_m + u.right_m));
    }
    if (row.fix < 0) continue;
    if (pairs >= 3 && (driven >= enough_m || row.t_s - in.t0_s > window_s)) break;
    const filters::Position f = in.fixes[static_cast<std::size_t>(row.fix)] - in.initial_pose.head<2>();
    dot += x * f(0) + y * f(1);
    cross += x * f(1) - y * f(0);
    reach = std::max(reach, std::hypot(x, y));
    ++pairs;
    t_end = row.t_s;
  }
  const double theta = (dot == 0.0 && cross == 0.0) ? 0.0 : std::atan2(cross, dot);
  *note = fmt::format(
      "start at the first fix (t = {:.3f} s); heading {:.4f} rad fitted to {} fixes over {:.1f} s "
      "({:.1f} m driven, {:.1f} m from the start)",
      in.t0_s, theta, pairs, t_end - in.t0_s, driven, reach);
  return theta;
}

// The wheels' geometry for turning odometry into wheel travel.
struct WheelGeometry {
  double Rl = 0.0, Rr = 0.0, tick_rev = 0.0;
};

// The odometry source (ticks, wheel rates or commands) and its geometry
// from the metadata.
WheelGeometry odometry_source(const tracks::Track& track, const ReplayInputOptions& options, ReplayInput& in) {
  const auto& meta = track.meta();
  WheelGeometry g;
  if (track.has_ticks() || track.has_wheel_rates()) {
    in.source = track.has_ticks() ? OdometrySource::ticks : OdometrySource::wheel_rates;
    g.Rl = require(track, meta.wheel_radius_left_m, "robot.wheel_radius_left");
    g.Rr = require(track, meta.wheel_radius_right_m, "robot.wheel_radius_right");
    in.wheel_base_m = require(track, meta.wheel_base_m, "robot.wheel_base");
    if (in.source == OdometrySource::ticks)
      g.tick_rev = require(track, meta.ticks_per_rev, "robot.ticks_per_rev");
  } else {
    in.source = OdometrySource::commands;
    in.wheel_base_m = meta.wheel_base_m.value_or(options.default_wheel_base_m);
  }
  return g;
}

bool has_fix(const tracks::Track& track, std::size_t i) {
  return track.at(tracks::Col::aps_x, i) && track.at(tracks::Col::aps_y, i);
}

// The start row (the first fix, or the first ground-truth position) and the
// initial pose there (by fixes: its heading is fitted later).
std::size_t start_row(const tracks::Track& track, bool by_fixes, const std::vector<double>& gx,
                      const std::vector<double>& gy, ReplayInput& in) {
  const std::size_t n = track.size();
  const bool has_theta = track.has(tracks::Col::gt_theta);
  std::size_t start = 0;
  if (by_fixes) {
    while (start < n && !has_fix(track, start)) ++start;
    if (start == n) fail_replay(track, "no row with a position fix");
    in.initial_pose << track.col(tracks::Col::aps_x)[start], track.col(tracks::Col::aps_y)[start],
        0.0;  // heading: below
  } else {
    while (start < n && (std::isnan(gx[start]) || std::isnan(gy[start]))) ++start;
    if (start == n) fail_replay(track, "no row with a ground-truth position");
    if (has_theta && std::isnan(track.col(tracks::Col::gt_theta)[start]))
      fail_replay(track,
                  fmt::format("the first ground-truth row (t = {} s) has no gt_theta", track.t()[start]));
    in.initial_pose << gx[start], gy[start], has_theta ? track.col(tracks::Col::gt_theta)[start] : 0.0;
  }
  return start;
}

// Odometry sample presence at row i.
bool odometry_at(const tracks::Track& track, OdometrySource source, std::size_t i) {
  switch (source) {
    case OdometrySource::ticks:
      return track.ticks_l()[i] != tracks::kNoTick && track.ticks_r()[i] != tracks::kNoTick;
    case OdometrySource::wheel_rates:
      return track.at(tracks::Col::omega_l, i) && track.at(tracks::Col::omega_r, i);
    case OdometrySource::commands: return track.at(tracks::Col::v_cmd, i) && track.at(tracks::Col::w_cmd, i);
  }
  return false;
}

// The wheels' travel between odometry rows p and i, dt apart.
filters::WheelTravel wheel_travel(const tracks::Track& track, const ReplayInput& in, const WheelGeometry& g,
                                  std::size_t p, std::size_t i, double dt) {
  const double two_pi = 2.0 * std::numbers::pi;
  const double Rl = g.Rl, Rr = g.Rr, tick_rev = g.tick_rev;
  filters::WheelTravel u;
  switch (in.source) {
    case OdometrySource::ticks:
      u.left_m = static_cast<double>(track.ticks_l()[i] - track.ticks_l()[p]) * two_pi * Rl / tick_rev;
      u.right_m = static_cast<double>(track.ticks_r()[i] - track.ticks_r()[p]) * two_pi * Rr / tick_rev;
      break;
    case OdometrySource::wheel_rates:  // trapezoidal rule
      u.left_m = 0.5 * (track.col(tracks::Col::omega_l)[p] + track.col(tracks::Col::omega_l)[i]) * Rl * dt;
      u.right_m = 0.5 * (track.col(tracks::Col::omega_r)[p] + track.col(tracks::Col::omega_r)[i]) * Rr * dt;
      break;
    case OdometrySource::commands: {  // zero-order hold of the previous command
      const double d = track.col(tracks::Col::v_cmd)[p] * dt;
      const double dth = track.col(tracks::Col::w_cmd)[p] * dt;
      u.left_m = d - 0.5 * dth * in.wheel_base_m;
      u.right_m = d + 0.5 * dth * in.wheel_base_m;
      break;
    }
  }
  return u;
}

// The fix at row i (with its variances where usable) as the row's fix.
void add_fix(const tracks::Track& track, std::size_t i, bool has_fix_var, ReplayInput& in, ReplayRow& row) {
  row.fix = static_cast<std::int32_t>(in.fixes.size());
  in.fixes.emplace_back(track.col(tracks::Col::aps_x)[i], track.col(tracks::Col::aps_y)[i]);
  const double vx = has_fix_var ? track.col(tracks::Col::aps_var_x)[i] : std::nan("");
  const double vy = has_fix_var ? track.col(tracks::Col::aps_var_y)[i] : std::nan("");
  const bool usable = vx > 0.0 && vy > 0.0 && std::isfinite(vx) && std::isfinite(vy);
  in.fix_var_x_m2.push_back(usable ? vx : std::nan(""));
  in.fix_var_y_m2.push_back(usable ? vy : std::nan(""));
}

// The rows after the start: each one's odometry step, fix and ground truth.
void read_rows(const tracks::Track& track, const WheelGeometry& geometry, std::size_t start,
               const std::vector<double>& gx, const std::vector<double>& gy, ReplayInput& in) {
  const std::size_t n = track.size();
  const auto& t = track.t();
  const bool has_theta = track.has(tracks::Col::gt_theta);
  const bool has_fix_var = track.has(tracks::Col::aps_var_x) && track.has(tracks::Col::aps_var_y);
  const bool has_gyro = track.has(tracks::Col::gyro_z);
  // The last odometry sample at or before the start row.
  std::ptrdiff_t last_odo = -1;
  for (std::size_t i = 0; i <= start; ++i)
    if (odometry_at(track, in.source, i)) last_odo = static_cast<std::ptrdiff_t>(i);
  double last_gyro = std::nan("");
  for (std::size_t i = 0; i <= start; ++i)
    if (has_gyro && track.at(tracks::Col::gyro_z, i)) last_gyro = track.col(tracks::Col::gyro_z)[i];

  for (std::size_t i = start + 1; i < n; ++i) {
    ReplayRow row;
    row.t_s = t[i];
    if (has_gyro && track.at(tracks::Col::gyro_z, i)) last_gyro = track.col(tracks::Col::gyro_z)[i];
    if (odometry_at(track, in.source, i)) {
      if (last_odo >= 0) {
        const auto p = static_cast<std::size_t>(last_odo);
        const double dt = t[i] - t[p];
        const filters::WheelTravel u = wheel_travel(track, in, geometry, p, i, dt);
        const double yaw_rate = std::isnan(last_gyro) ? (u.right_m - u.left_m) / in.wheel_base_m / dt
                                                      : last_gyro;
        row.step = static_cast<std::int32_t>(in.steps.size());
        in.steps.push_back(u);
        in.abs_yaw_rate_rad_s.push_back(std::abs(yaw_rate));
      }
      last_odo = static_cast<std::ptrdiff_t>(i);
    }
    if (has_fix(track, i)) add_fix(track, i, has_fix_var, in, row);
    if (!std::isnan(gx[i]) && !std::isnan(gy[i])) {
      row.gt = static_cast<std::int32_t>(in.gt.size());
      in.gt.emplace_back(gx[i], gy[i]);
      in.gt_theta_rad.push_back(has_theta ? track.col(tracks::Col::gt_theta)[i] : std::nan(""));
    }
    if (row.step >= 0 || row.fix >= 0 || row.gt >= 0) in.rows.push_back(row);
  }
}

}  // namespace

ReplayInput build_replay_input(const tracks::Track& track, const ReplayInputOptions& options) {
  ReplayInput in;
  in.track_name = track.name();
  if (!track.has_odometry()) fail_replay(track, "no odometry columns (ticks_*, omega_* or v_cmd/w_cmd)");
  const bool by_fixes = options.reference == ReplayReference::fixes;
  in.reference_is_fixes = by_fixes;
  if (!by_fixes && !track.has_gt())
    fail_replay(track,
                "no ground truth (gt_x, gt_y): metrics need it (a track whose only reference is its position "
                "fixes is tuned with the fix cross-validation modes 8 and 9)");
  if (by_fixes && !track.has_aps())
    fail_replay(track, "no position fixes (aps_x, aps_y) to start from and score against");
  const WheelGeometry geometry = odometry_source(track, options, in);

  const std::vector<double> none(track.size(), std::nan(""));
  const auto& gx = track.has(tracks::Col::gt_x) ? track.col(tracks::Col::gt_x) : none;
  const auto& gy = track.has(tracks::Col::gt_y) ? track.col(tracks::Col::gt_y) : none;
  const std::size_t start = start_row(track, by_fixes, gx, gy, in);
  in.t0_s = track.t()[start];
  read_rows(track, geometry, start, gx, gy, in);

  if (!by_fixes && in.gt.empty()) fail_replay(track, "only one ground-truth row: nothing to compare with");
  if (by_fixes) {
    if (in.fixes.empty()) fail_replay(track, "only one position fix: nothing to compare with");
    // The fixes' variance: the first fix's own, else the noise model's default.
    const double var = std::isnan(in.fix_var_x_m2.front())
                           ? filters::NoiseParams{}.q_x_m2
                           : 0.5 * (in.fix_var_x_m2.front() + in.fix_var_y_m2.front());
    in.initial_pose(2) = initial_heading_from_fixes(in, var, options.heading_window_s, &in.initial_pose_note);
    const double heading_sd_rad = 10.0 * std::numbers::pi / 180.0;
    in.initial_cov = filters::Pose(var, var, heading_sd_rad * heading_sd_rad).asDiagonal();
  }
  return in;
}

ReplayInput build_replay_input_any(const tracks::Track& track) {
  if (track.has_gt()) return build_replay_input(track);
  ReplayInputOptions o;
  o.reference = ReplayReference::fixes;
  return build_replay_input(track, o);
}

}  // namespace odotune::objectives
