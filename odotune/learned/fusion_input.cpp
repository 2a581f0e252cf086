#include <odotune/learned/fusion_input.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/why.h>
#include <odotune/objectives/pose_series.h>
#include <odotune/objectives/track_samples.h>
#include <odotune/tracks/body_velocity.h>
#include <odotune/tracks/odometry_input.h>

namespace odotune::learned {

namespace {

// Upper bound of rate_hz [Hz] (beyond any encoder rate of the reference
// tracks; keeps the step count bounded).
constexpr double kMaxRateHz = 1000.0;
// Time stamps closer than this are the same instant [s]: t[0] + k·Δt against
// a row stamp k'/rate written with a few decimals.
constexpr double kSameInstantS = 1e-6;

[[noreturn]] void fail(const std::string& track, const std::string& what) {
  throw std::invalid_argument(fmt::format("track '{}': {}", track, what));
}

// A cumulative wheel count sampled at the odometry rows, interpolated
// linearly between them; a row stamped within kSameInstantS of t_s gives its
// own count (t[0] + k·Δt and a row stamp k'/rate differ in the last bits).
// Clamped at the ends, which the step times never pass by more than
// kSameInstantS.
double count_at(const std::vector<double>& t, const std::vector<double>& c, double t_s) {
  if (t_s <= t.front()) return c.front();
  if (t_s >= t.back()) return c.back();
  const auto after = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), t_s + kSameInstantS) -
                                              t.begin());
  const std::size_t lo = after - 1;  // ≥ 0: t_s > t.front()
  if (std::abs(t[lo] - t_s) <= kSameInstantS || lo + 1 == t.size()) return c[lo];
  const double f = (t_s - t[lo]) / (t[lo + 1] - t[lo]);
  return c[lo] + f * (c[lo + 1] - c[lo]);
}

// The ground-truth pose at t_s: a sample stamped within kSameInstantS of t_s
// itself, else the linear interpolation (pose_series.h).
std::optional<objectives::PlanarPose> gt_pose_at(const objectives::PoseSeries& gt, double t_s) {
  if (gt.size() == 0) return std::nullopt;
  const auto it = std::lower_bound(gt.t.begin(), gt.t.end(), t_s - kSameInstantS);
  if (it != gt.t.end() && std::abs(*it - t_s) <= kSameInstantS) {
    const auto i = static_cast<std::size_t>(it - gt.t.begin());
    return objectives::PlanarPose{gt.x[i], gt.y[i], gt.theta[i]};
  }
  return objectives::interpolate_pose(gt, t_s, objectives::kMaxGtGapS);
}

// The robot's nominal geometry (or the options' calibrated one) and
// ticks_per_rev from the metadata into `in`.
void read_nominal(const tracks::Track& track, FusionInput& in, const FusionInputOptions& options) {
  const std::string& name = track.name();
  std::string why;
  const tracks::TrackMeta& meta = track.meta();
  auto require = [&](const std::optional<double>& v, const char* key) {
    if (!v)
      fail(name, fmt::format("metadata '{}' is missing: fusion needs the robot's nominal wheel "
                             "radii, wheel base and ticks_per_rev",
                             key));
    return *v;
  };
  in.nominal.wheel_radius_left_m = require(meta.wheel_radius_left_m, "robot.wheel_radius_left");
  in.nominal.wheel_radius_right_m = require(meta.wheel_radius_right_m, "robot.wheel_radius_right");
  in.nominal.wheel_base_m = require(meta.wheel_base_m, "robot.wheel_base");
  in.ticks_per_rev = require(meta.ticks_per_rev, "robot.ticks_per_rev");
  if (!in.nominal.IsValid(&why)) fail(name, "nominal robot metadata: " + why);
  if (options.geometry) in.nominal = *options.geometry;
  if (!(std::isfinite(in.ticks_per_rev) && in.ticks_per_rev > 0.0))
    fail(name, fmt::format("robot.ticks_per_rev = {} must be a finite number > 0", in.ticks_per_rev));
}

// Cumulative wheel counts at the odometry rows.
struct OdometryCounts {
  std::vector<double> t, cum_l, cum_r;
};

// From ticks: the count itself (relative to the first row, so the doubles
// stay exact). From omega: the trapezoid integral of ω, in counts.
OdometryCounts odometry_counts(const tracks::Track& track, bool from_ticks, double counts_per_rad) {
  const auto& tt = track.t();
  OdometryCounts oc;
  std::vector<double>& odo_t = oc.t;
  std::vector<double>& cum_l = oc.cum_l;
  std::vector<double>& cum_r = oc.cum_r;
  std::vector<std::size_t> odo_row;  // the odometry rows' indices in the track
  std::int64_t first_l = 0, first_r = 0;
  for (std::size_t i = 0; i < track.size(); ++i) {
    if (from_ticks) {
      if (track.ticks_l()[i] == tracks::kNoTick || track.ticks_r()[i] == tracks::kNoTick) continue;
      if (odo_t.empty()) first_l = track.ticks_l()[i], first_r = track.ticks_r()[i];
      cum_l.push_back(static_cast<double>(track.ticks_l()[i] - first_l));
      cum_r.push_back(static_cast<double>(track.ticks_r()[i] - first_r));
    } else {
      if (!track.at(tracks::Col::omega_l, i) || !track.at(tracks::Col::omega_r, i)) continue;
      // Trapezoid over the omega rows: φ_i = φ_{i−1} + (ω_{i−1} + ω_i)/2 · Δt.
      if (odo_t.empty()) {
        cum_l.push_back(0.0);
        cum_r.push_back(0.0);
      } else {
        const std::size_t p = odo_t.size() - 1;  // previous omega row (index in odo_t)
        const std::size_t pi = odo_row.back();   // ... and in the track
        const double dt = tt[i] - tt[pi];
        cum_l.push_back(cum_l[p] +
                        0.5 * (track.col(tracks::Col::omega_l)[pi] + track.col(tracks::Col::omega_l)[i]) * dt *
                            counts_per_rad);
        cum_r.push_back(cum_r[p] +
                        0.5 * (track.col(tracks::Col::omega_r)[pi] + track.col(tracks::Col::omega_r)[i]) * dt *
                            counts_per_rad);
      }
    }
    odo_t.push_back(tt[i]);
    odo_row.push_back(i);
  }
  return oc;
}

// The mean body velocity over each step under the zero-order hold of
// odotune/tracks/body_velocity.h (delayed by `delay_s`, scaled: FusionInputOptions);
// no wheel increments (NaN).
void body_velocity_per_step(const tracks::BodyVelocityIntegral& body, const FusionInputOptions& o,
                            FusionInput& in) {
  const std::size_t n = in.t.size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  in.dticks_l.assign(n, nan);
  in.dticks_r.assign(n, nan);
  in.v_kin.assign(n, 0.0);
  in.w_kin.assign(n, 0.0);
  for (std::size_t k = 1; k < n; ++k) {
    const auto vw = body.mean(in.t[k - 1], in.t[k], o.twist.delay_s);
    in.v_kin[k] = o.twist.scale_v * vw[0];
    in.w_kin[k] = o.twist.scale_w * vw[1];
  }
}

// Increments and kinematic odometry (paper eqs. 1–2) per step.
void increments_and_kinematics(const OdometryCounts& oc, double counts_per_rad, FusionInput& in) {
  const std::size_t n = in.t.size();
  in.dticks_l.assign(n, 0.0);
  in.dticks_r.assign(n, 0.0);
  in.v_kin.assign(n, 0.0);
  in.w_kin.assign(n, 0.0);
  double prev_l = count_at(oc.t, oc.cum_l, in.t[0]);
  double prev_r = count_at(oc.t, oc.cum_r, in.t[0]);
  for (std::size_t k = 1; k < n; ++k) {
    const double cl = count_at(oc.t, oc.cum_l, in.t[k]);
    const double cr = count_at(oc.t, oc.cum_r, in.t[k]);
    in.dticks_l[k] = cl - prev_l;
    in.dticks_r[k] = cr - prev_r;
    prev_l = cl;
    prev_r = cr;
    // Eq. 1: wheel rate ω = 2π·Δct/(encRes·ΔT); eq. 2 with the radii and D.
    const double rad_per_count_s = 1.0 / (counts_per_rad * in.dt_s);
    const filters::BodyVelocity b = filters::body_velocity(in.nominal, in.dticks_l[k] * rad_per_count_s,
                                                           in.dticks_r[k] * rad_per_count_s);
    in.v_kin[k] = b.v_m_s;
    in.w_kin[k] = b.w_rad_s;
  }
}

// Sensors per step: power and gyro averaged over the rows in (t[k−1], t[k]],
// the last external velocity and the last position fix among them.
void sensors_per_step(const tracks::Track& track, const FusionInputOptions& options, FusionInput& in) {
  const auto& tt = track.t();
  const std::size_t n = in.t.size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  in.power_l.assign(n, nan);
  in.power_r.assign(n, nan);
  in.v_ext.assign(n, nan);
  in.w_ext.assign(n, nan);
  in.v_ext_var.assign(n, nan);
  in.w_ext_var.assign(n, nan);
  in.gyro_z.assign(n, nan);
  for (auto* v : {&in.fix_x, &in.fix_y, &in.fix_var_x, &in.fix_var_y}) v->assign(n, nan);
  const bool track_fixes = track.has_aps();
  const bool fix_vars = track.has(tracks::Col::aps_var_x) && track.has(tracks::Col::aps_var_y);
  const bool track_power = track.has(tracks::Col::power_l) && track.has(tracks::Col::power_r);
  const bool track_ext = track.has(tracks::Col::v_ext) && track.has(tracks::Col::w_ext);
  const bool track_gyro = track.has(tracks::Col::gyro_z);
  std::size_t i = 0;  // first track row not yet assigned to a step
  // Rows at or before t[0] belong to no step.
  while (i < track.size() && tt[i] <= in.t[0] + kSameInstantS) ++i;
  for (std::size_t k = 1; k < n; ++k) {
    double sum_pl = 0.0, sum_pr = 0.0, sum_g = 0.0;
    int n_pl = 0, n_pr = 0, n_g = 0;
    for (; i < track.size() && tt[i] <= in.t[k] + kSameInstantS; ++i) {
      if (track_power && track.at(tracks::Col::power_l, i))
        sum_pl += track.col(tracks::Col::power_l)[i], ++n_pl;
      if (track_power && track.at(tracks::Col::power_r, i))
        sum_pr += track.col(tracks::Col::power_r)[i], ++n_pr;
      if (track_gyro && track.at(tracks::Col::gyro_z, i)) sum_g += track.col(tracks::Col::gyro_z)[i], ++n_g;
      if (track_fixes && track.at(tracks::Col::aps_x, i) && track.at(tracks::Col::aps_y, i)) {
        in.fix_x[k] = track.col(tracks::Col::aps_x)[i];
        in.fix_y[k] = track.col(tracks::Col::aps_y)[i];
        in.fix_var_x[k] = fix_vars ? track.col(tracks::Col::aps_var_x)[i] : nan;
        in.fix_var_y[k] = fix_vars ? track.col(tracks::Col::aps_var_y)[i] : nan;
        in.has_fixes = true;
      }
      if (track_ext && track.at(tracks::Col::v_ext, i) && track.at(tracks::Col::w_ext, i)) {
        in.v_ext[k] = track.col(tracks::Col::v_ext)[i];
        in.w_ext[k] = track.col(tracks::Col::w_ext)[i];
        in.v_ext_var[k] = objectives::positive_or(track.col(tracks::Col::v_ext_var), i,
                                                  options.default_ext_var_v);
        in.w_ext_var[k] = objectives::positive_or(track.col(tracks::Col::w_ext_var), i,
                                                  options.default_ext_var_w);
        in.has_ext = true;
      }
    }
    if (n_pl > 0) in.power_l[k] = sum_pl / n_pl;
    if (n_pr > 0) in.power_r[k] = sum_pr / n_pr;
    if (n_pl > 0 && n_pr > 0) in.has_power = true;
    if (n_g > 0) {
      in.gyro_z[k] = sum_g / n_g;
      in.has_gyro = true;
    }
  }
}

// The ground-truth pose at each step and the true body velocities between
// steps.
void ground_truth_per_step(const tracks::Track& track, FusionInput& in) {
  const std::size_t n = in.t.size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  in.gt_x.assign(n, nan);
  in.gt_y.assign(n, nan);
  in.gt_theta.assign(n, nan);
  in.v_true.assign(n, 0.0);
  in.w_true.assign(n, 0.0);
  const objectives::PoseSeries gt = objectives::ground_truth_series(track);
  for (std::size_t k = 0; k < n; ++k) {
    const auto p = gt_pose_at(gt, in.t[k]);
    if (!p) continue;
    in.gt_x[k] = p->x_m;
    in.gt_y[k] = p->y_m;
    in.gt_theta[k] = p->theta_rad;
  }
  for (std::size_t k = 1; k < n; ++k) {
    const double dx = in.gt_x[k] - in.gt_x[k - 1], dy = in.gt_y[k] - in.gt_y[k - 1];
    const double dth = in.gt_theta[k] - in.gt_theta[k - 1];
    const double mid = 0.5 * (in.gt_theta[k] + in.gt_theta[k - 1]);
    in.w_true[k] = dth / in.dt_s;
    in.v_true[k] = (dx * std::cos(mid) + dy * std::sin(mid)) / in.dt_s;
    if (std::isfinite(in.v_true[k]) && std::isfinite(in.w_true[k])) in.has_gt = true;
  }
}

// The track's commands per step (FusionInput::v_cmd), when it has any.
void commands_per_step(const tracks::Track& track, FusionInput& in) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  in.v_cmd.assign(in.size(), nan);
  in.w_cmd.assign(in.size(), nan);
  in.has_cmd = false;
  if (!track.has_cmd()) return;
  const tracks::BodyVelocityIntegral body(track);
  if (body.size() < 2) return;
  for (std::size_t k = 1; k < in.size(); ++k) {
    if (in.t[k] <= body.t().front() || in.t[k - 1] >= body.t().back()) continue;
    const auto m = body.mean(in.t[k - 1], in.t[k]);
    in.v_cmd[k] = m[0];
    in.w_cmd[k] = m[1];
    in.has_cmd = true;
  }
}

// External velocities from the ground truth (FusionInputOptions::ext_from_gt_hz):
// each reference instant's velocity goes to the step holding it.
void ext_from_ground_truth(const tracks::Track& track, const FusionInputOptions& o, FusionInput& in) {
  const objectives::PoseSeries gt = objectives::ground_truth_series(track);
  const double period = 1.0 / o.ext_from_gt_hz;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (auto* v : {&in.v_ext, &in.w_ext, &in.v_ext_var, &in.w_ext_var}) v->assign(in.size(), nan);
  in.has_ext = false;
  if (gt.size() < 2) return;
  for (std::size_t k = 1; k < in.size(); ++k) {
    // The last reference instant inside (t[k−1], t[k]].
    const double j = std::floor(in.t[k] / period + 1e-9);
    const double tj = j * period;
    if (tj <= in.t[k - 1]) continue;
    const auto vw = objectives::central_difference_velocity(gt, tj, 0.5 * period, 2.0 * period);
    if (!vw) continue;
    in.v_ext[k] = vw->v_m_s;
    in.w_ext[k] = vw->w_rad_s;
    in.v_ext_var[k] = o.default_ext_var_v;
    in.w_ext_var[k] = o.default_ext_var_w;
    in.has_ext = true;
  }
}

}  // namespace

FusionInput slice_fusion_input(const FusionInput& in, std::size_t first, std::size_t end) {
  end = std::min(end, in.size());
  first = std::min(first, end);
  FusionInput out = in;
  const auto cut = [first, end](std::vector<double>& v) {
    v = std::vector<double>(v.begin() + static_cast<std::ptrdiff_t>(first),
                            v.begin() + static_cast<std::ptrdiff_t>(end));
  };
  for (auto* v : {&out.t,       &out.dticks_l, &out.dticks_r, &out.v_kin,     &out.w_kin,     &out.power_l,
                  &out.power_r, &out.v_ext,    &out.w_ext,    &out.v_ext_var, &out.w_ext_var, &out.gyro_z,
                  &out.v_cmd,   &out.w_cmd,    &out.fix_x,    &out.fix_y,     &out.fix_var_x, &out.fix_var_y,
                  &out.gt_x,    &out.gt_y,     &out.gt_theta, &out.v_true,    &out.w_true})
    cut(*v);
  const auto any = [](const std::vector<double>& v) {
    return std::any_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
  };
  out.has_gt = any(out.v_true) && any(out.gt_x);
  out.has_power = any(out.power_l) && any(out.power_r);
  out.has_ext = any(out.v_ext);
  out.has_gyro = any(out.gyro_z);
  out.has_fixes = any(out.fix_x);
  out.has_cmd = any(out.v_cmd);
  return out;
}

bool FusionInputOptions::IsValid(std::string* why) const {
  if (!(std::isfinite(rate_hz) && rate_hz > 0.0 && rate_hz <= kMaxRateHz))
    return core::invalid(why, fmt::format("rate_hz = {} must be in (0, {}] Hz", rate_hz, kMaxRateHz));
  std::string inner;
  if (!(std::isfinite(ext_from_gt_hz) && ext_from_gt_hz >= 0.0 && ext_from_gt_hz <= 100.0))
    return core::invalid(why, fmt::format("ext_from_gt_hz = {} must be in [0, 100] Hz (0: the track's v_ext)",
                                          ext_from_gt_hz));
  if (geometry && !geometry->IsValid(&inner)) return core::invalid(why, "geometry: " + inner);
  if (!twist.IsValid(&inner)) return core::invalid(why, "twist: " + inner);
  if (!(std::isfinite(default_ext_var_v) && default_ext_var_v > 0.0))
    return core::invalid(why, fmt::format("default_ext_var_v = {} must be a finite number > 0 [(m/s)^2]",
                                          default_ext_var_v));
  if (!(std::isfinite(default_ext_var_w) && default_ext_var_w > 0.0))
    return core::invalid(why, fmt::format("default_ext_var_w = {} must be a finite number > 0 [(rad/s)^2]",
                                          default_ext_var_w));
  return true;
}

FusionInput build_fusion_input(const tracks::Track& track, const FusionInputOptions& options) {
  const std::string& name = track.name();
  std::string why;
  if (!options.IsValid(&why)) fail(name, "invalid fusion input options: " + why);

  FusionInput in;
  in.track_name = name;
  in.input = tracks::track_odometry_input(track, options.input);
  const bool wheels = in.input == tracks::OdometryInput::wheels;
  double counts_per_rad = 0.0;
  OdometryCounts oc;
  std::optional<tracks::BodyVelocityIntegral> body;
  if (wheels) {
    read_nominal(track, in, options);
    counts_per_rad = in.ticks_per_rev / (2.0 * std::numbers::pi);
    oc = odometry_counts(track, track.has_ticks(), counts_per_rad);
  } else {
    body.emplace(track);
  }
  const std::vector<double>& odo_t = wheels ? oc.t : body->t();
  if (odo_t.size() < 2)
    fail(name,
         fmt::format("fewer than two {} rows: no odometry interval to fuse", tracks::to_string(in.input)));

  // --- step times ----------------------------------------------------------
  in.dt_s = 1.0 / options.rate_hz;
  const double t0 = odo_t.front();
  const double t_end = odo_t.back() + kSameInstantS;
  for (std::size_t k = 0;; ++k) {
    const double tk = t0 + static_cast<double>(k) * in.dt_s;
    if (tk > t_end) break;
    in.t.push_back(tk);
  }
  const std::size_t n = in.t.size();
  if (n < 2)
    fail(name, fmt::format("fewer than 2 steps of {} s: the odometry spans {} s", in.dt_s,
                           odo_t.back() - odo_t.front()));

  if (wheels)
    increments_and_kinematics(oc, counts_per_rad, in);
  else
    body_velocity_per_step(*body, options, in);
  sensors_per_step(track, options, in);
  commands_per_step(track, in);
  if (options.ext_from_gt_hz > 0.0) ext_from_ground_truth(track, options, in);
  ground_truth_per_step(track, in);
  return in;
}

}  // namespace odotune::learned
