#include <odotune/objectives/rl_track.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/why.h>
#include <odotune/filters/rl_ekf.h>
#include <odotune/objectives/replay_input.h>
#include <odotune/objectives/rl_protocols.h>
#include <odotune/rlnode/sample_recording.h>

namespace odotune::objectives {

bool RlTrackOptions::IsValid(std::string* why) const {
  for (double v : {odometry_var_vx, odometry_var_vyaw, gyro_var}) {
    if (!(v > 0.0 && std::isfinite(v)))
      return core::invalid(why, fmt::format("an input variance of {}, expected a finite value > 0", v));
  }
  if (fix_sigma_m && !(*fix_sigma_m > 0.0 && std::isfinite(*fix_sigma_m)))
    return core::invalid(why, fmt::format("--fix-sigma-m {}, expected a finite value > 0", *fix_sigma_m));
  if (!(heading_window_s > 0.0))
    return core::invalid(why, fmt::format("heading window {} s, expected > 0", heading_window_s));
  if (wheels && twist) return core::invalid(why, "a wheel and a twist calibration; expected one");
  if (wheels && !wheels->IsValid(why)) return false;
  if (twist && !twist->IsValid(why)) return false;
  return true;
}

namespace {

std::int64_t ns_of(double t_s) { return static_cast<std::int64_t>(std::llround(t_s * 1e9)); }

[[noreturn]] void fail_rl_track(const std::filesystem::path& file, const std::string& what) {
  throw std::invalid_argument(fmt::format("{}: {}", file.string(), what));
}

// The track with aps_var_x, aps_var_y filled from σ where it gives none.
tracks::Track with_fix_variances(const tracks::Track& track, const std::filesystem::path& file,
                                 const RlTrackOptions& o) {
  const bool has_var = track.has(tracks::Col::aps_var_x) && track.has(tracks::Col::aps_var_y);
  if (!track.has_aps() || has_var) return track;  // the track's own variances win over --fix-sigma-m
  if (!o.fix_sigma_m) {
    fail_rl_track(
        file, "its fixes have no variances (aps_var_x, aps_var_y); expected them (odotune fixes writes them) "
              "or --fix-sigma-m");
  }
  tracks::TrackData d = track.data();
  std::vector<double>& vx = d.ensure(tracks::Col::aps_var_x);
  std::vector<double>& vy = d.ensure(tracks::Col::aps_var_y);
  const double var = *o.fix_sigma_m * *o.fix_sigma_m;
  for (std::size_t i = 0; i < d.t.size(); ++i) {
    const bool fix = !std::isnan(d.col(tracks::Col::aps_x)[i]) && !std::isnan(d.col(tracks::Col::aps_y)[i]);
    vx[i] = fix ? var : std::nan("");
    vy[i] = fix ? var : std::nan("");
  }
  return tracks::Track(std::move(d));
}

// The odometry twist per sample: encoder travel differenced per step, or the
// body velocities as they stand.
std::vector<rlnode::TwistSample> odometry_of(const tracks::Track& track, tracks::OdometryInput input,
                                             const ReplayInput& in,
                                             const std::optional<filters::TwistCorrection>& correction) {
  std::vector<rlnode::TwistSample> out;
  if (input == tracks::OdometryInput::wheels) {
    double prev_t = std::nan("");
    for (const ReplayRow& row : in.rows) {
      if (row.step < 0) continue;
      const filters::WheelTravel& u = in.steps[static_cast<std::size_t>(row.step)];
      if (!std::isnan(prev_t)) {
        const double dt = row.t_s - prev_t;
        out.push_back({ns_of(row.t_s), 0.5 * (u.left_m + u.right_m) / dt,
                       (u.right_m - u.left_m) / in.wheel_base_m / dt});
      }
      prev_t = row.t_s;
    }
    return out;
  }
  const filters::TwistCorrection c = correction.value_or(filters::TwistCorrection{});
  for (std::size_t i = 0; i < track.size(); ++i) {
    if (track.at(tracks::Col::v_cmd, i) && track.at(tracks::Col::w_cmd, i)) {
      out.push_back({ns_of(track.t()[i] + c.delay_s), c.scale_v * track.col(tracks::Col::v_cmd)[i],
                     c.scale_w * track.col(tracks::Col::w_cmd)[i]});
    }
  }
  return out;
}

// The track with a wheel calibration written into its geometry.
tracks::Track with_geometry(const tracks::Track& track, const filters::OdometryParams& p) {
  tracks::TrackData d = track.data();
  d.meta.wheel_radius_left_m = p.wheel_radius_left_m;
  d.meta.wheel_radius_right_m = p.wheel_radius_right_m;
  d.meta.wheel_base_m = p.wheel_base_m;
  return tracks::Track(std::move(d));
}

rlnode::SampleStreams streams_of(const tracks::Track& track, const std::filesystem::path& file,
                                 tracks::OdometryInput input, const ReplayInput& in, const RlTrackOptions& o) {
  rlnode::SampleStreams st;
  st.name = file.string();
  st.odometry = odometry_of(track, input, in, o.twist);
  st.odometry_var_vx = o.odometry_var_vx;
  st.odometry_var_vyaw = o.odometry_var_vyaw;
  st.gyro_var = o.gyro_var;
  for (std::size_t i = 0; i < track.size(); ++i) {
    const double t = track.t()[i];
    if (track.at(tracks::Col::gyro_z, i)) st.gyro.push_back({ns_of(t), track.col(tracks::Col::gyro_z)[i]});
    if (track.at(tracks::Col::aps_x, i) && track.at(tracks::Col::aps_y, i)) {
      st.fixes.push_back({ns_of(t), track.col(tracks::Col::aps_x)[i], track.col(tracks::Col::aps_y)[i],
                          track.col(tracks::Col::aps_var_x)[i], track.col(tracks::Col::aps_var_y)[i]});
    }
  }
  return st;
}

std::vector<TruthSample> truth_of(const tracks::Track& track) {
  std::vector<TruthSample> out;
  if (!track.has_gt()) return out;
  for (std::size_t i = 0; i < track.size(); ++i) {
    if (track.at(tracks::Col::gt_x, i) && track.at(tracks::Col::gt_y, i))
      out.push_back({ns_of(track.t()[i]), track.col(tracks::Col::gt_x)[i], track.col(tracks::Col::gt_y)[i]});
  }
  return out;
}

// gt_theta at the first row at or after t_s (NaN without one).
double truth_heading(const tracks::Track& track, double t_s) {
  if (!track.has(tracks::Col::gt_theta)) return std::nan("");
  for (std::size_t i = 0; i < track.size(); ++i)
    if (track.t()[i] >= t_s && track.at(tracks::Col::gt_theta, i)) return track.col(tracks::Col::gt_theta)[i];
  return std::nan("");
}

}  // namespace

RlTrack load_rl_track(const tracks::Track& original, const std::filesystem::path& file,
                      const rlnode::RlParams& params, const RlTrackOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) fail_rl_track(file, why);
  const rlnode::SampleRoles roles = rlnode::sample_roles(params, file.string());
  const tracks::Track fixed = with_fix_variances(original, file, options);
  const tracks::Track track = options.wheels ? with_geometry(fixed, *options.wheels) : fixed;
  RlTrack out;
  out.file = file;
  out.odometry = tracks::track_odometry_input(track, options.odometry);
  if ((options.wheels && out.odometry != tracks::OdometryInput::wheels) ||
      (options.twist && out.odometry == tracks::OdometryInput::wheels)) {
    fail_rl_track(
        file, fmt::format("a calibration of the {} for its {} odometry; expected a calibration of its input",
                          options.wheels ? "wheels" : "body velocity", tracks::to_string(out.odometry)));
  }
  ReplayInputOptions ro;
  ro.heading_window_s = options.heading_window_s;
  if (roles.fixes >= 0) {
    if (!track.has_aps())
      fail_rl_track(file, fmt::format("{} fuses position fixes, which the track does not have (aps_x, aps_y); "
                                      "expected them (odotune fixes makes them)",
                                      params.sensors[roles.fixes].name));
    ro.reference = ReplayReference::fixes;
  }
  const ReplayInput in = build_replay_input(track, ro);
  rlnode::RlParams p = params;
  rlnode::Vector15 x0 = rlnode::Vector15::Zero();
  x0[filters::rl::kX] = in.initial_pose(0);
  x0[filters::rl::kY] = in.initial_pose(1);
  x0[filters::rl::kYaw] = in.initial_pose(2);
  p.initial_state = x0;
  out.rec = rlnode::load_sample_recording(p, streams_of(track, file, out.odometry, in, options),
                                          ns_of(in.t0_s));
  out.truth = truth_of(track);
  out.start_note = roles.fixes >= 0
                       ? in.initial_pose_note
                       : fmt::format("start at the first ground-truth pose (t = {:.3f} s)", in.t0_s);
  const double gt_heading = truth_heading(track, in.t0_s);
  out.initial_heading_error_rad = filters::rl::normalize_angle(in.initial_pose(2) - gt_heading);
  return out;
}

namespace {

// The ground truth at t (linear between the samples around it), or false when
// none lies within 0.5 s.
bool truth_at(std::span<const TruthSample> truth, std::int64_t t, double* x, double* y) {
  constexpr std::int64_t kNear = 500'000'000;
  auto it = std::lower_bound(truth.begin(), truth.end(), t,
                             [](const TruthSample& s, std::int64_t v) { return s.t_ns < v; });
  if (it != truth.end() && it->t_ns == t) {
    *x = it->x;
    *y = it->y;
    return true;
  }
  if (it == truth.begin() || it == truth.end()) return false;
  const TruthSample& b = *it;
  const TruthSample& a = *(it - 1);
  if (t - a.t_ns > kNear || b.t_ns - t > kNear) return false;
  const double w = static_cast<double>(t - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  *x = a.x + w * (b.x - a.x);
  *y = a.y + w * (b.y - a.y);
  return true;
}

}  // namespace

TruthScore truth_score(std::span<const TruthSample> truth, std::span<const rlnode::TrajectoryPoint> trajectory,
                       std::int64_t from_ns, std::int64_t until_ns) {
  TruthScore s;
  double sq = 0.0, abs = 0.0;
  for (const rlnode::TrajectoryPoint& p : trajectory) {
    if (p.time_ns < from_ns || p.time_ns >= until_ns) continue;
    double x = 0.0, y = 0.0;
    if (!truth_at(truth, p.time_ns, &x, &y)) continue;
    const double e = std::hypot(p.state[filters::rl::kX] - x, p.state[filters::rl::kY] - y);
    if (!std::isfinite(e)) s.finite = false;
    sq += e * e;
    abs += e;
    s.max_m = std::max(s.max_m, e);
    ++s.samples;
  }
  const auto n = static_cast<double>(s.samples);
  s.rmse_m = s.samples > 0 ? std::sqrt(sq / n) : std::numeric_limits<double>::quiet_NaN();
  s.mae_m = s.samples > 0 ? abs / n : std::numeric_limits<double>::quiet_NaN();
  return s;
}

TruthScore pooled(std::span<const TruthScore> scores) {
  std::vector<detail::RmsPart> parts;
  for (const TruthScore& t : scores) parts.push_back({t.samples, t.rmse_m, t.mae_m, t.max_m, t.finite});
  const detail::RmsPart p = detail::pooled_parts(parts);
  return {p.rmse, p.mae, p.max, p.n, p.finite};
}

RlTrackScores score_rl_track(const RlTrack& track, const rlnode::ReplaySettings& settings,
                             const RlTuneOptions& options, bool keep_trajectory) {
  const rlnode::Recording& rec = track.rec;
  RlTrackScores s;
  rlnode::ReplayOutput run = rlnode::replay(rec, rlnode::make_schedule(rec), settings, true);
  s.run = truth_score(track.truth, run.trajectory);
  s.processed = run.processed;
  s.rejected = run.rejected;
  if (!run.finite) s.run.finite = false;
  if (keep_trajectory) s.trajectory = std::move(run.trajectory);
  if (rec.fixes.empty()) return s;
  const std::vector<OutageWindow> windows = outage_windows(rec, options.outage_s, options.outage_stride_s,
                                                           after_warmup(rec, options.warmup_s),
                                                           std::numeric_limits<std::int64_t>::max());
  const OutageReplays outages(rec, windows, std::numeric_limits<std::int64_t>::max());
  std::vector<TruthScore> each;
  std::vector<rlnode::ReplayOutput> scored;  // each window's withheld fixes, without its path
  outages.each_window(settings, [&](const OutageWindow& w, const rlnode::ReplayOutput& o) {
    each.push_back(truth_score(track.truth, o.trajectory, w.start_ns, w.end_ns));
    if (!o.finite) each.back().finite = false;
    rlnode::ReplayOutput& fixes = scored.emplace_back();
    fixes.scored = o.scored;
    fixes.finite = o.finite;
  });
  s.outages = pooled(each);
  s.windows = windows.size();
  // The same windows' fixes, scored as OutageReplays::score scores them.
  s.outage_fixes = score_of(scored);
  std::vector<rlnode::Schedule> folds;
  for (const auto& roles :
       heldout_fix_folds(rec, options.folds, options.block_s, std::numeric_limits<std::int64_t>::max()))
    folds.push_back(rlnode::make_schedule(rec, roles));
  s.heldout_fixes = replay_score(rec, folds, settings);
  return s;
}

}  // namespace odotune::objectives
