#include <odotune/calibration/online_pose.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/enum_names.h>
#include <odotune/core/robust_stats.h>
#include <odotune/core/why.h>

namespace odotune::calibration {

namespace {

bool non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

// The variances of fix i: the track's own, else fix_sd_m².
std::pair<double, double> fix_variances(const CalibrationInput& in, std::size_t i, const OnlinePoseOptions& o) {
  const double vx = in.fix_var_x.empty() ? std::nan("") : in.fix_var_x[i];
  const double vy = in.fix_var_y.empty() ? std::nan("") : in.fix_var_y[i];
  if (std::isfinite(vx) && std::isfinite(vy) && vx > 0.0 && vy > 0.0) return {vx, vy};
  if (o.fix_sd_m) return {*o.fix_sd_m * *o.fix_sd_m, *o.fix_sd_m * *o.fix_sd_m};
  throw std::invalid_argument(fmt::format(
      "track '{}': the fix at t = {} s has no usable variance (aps_var_x, aps_var_y); give the fixes' sd "
      "(--fix-sigma-m)",
      in.track_name, in.fix_t[i]));
}

std::optional<filters::PlanarPose> known_start(const CalibrationInput& in) {
  for (std::size_t r = 0; r < in.t.size(); ++r)
    if (in.has_gt_row(r)) {
      if (r > 0 && in.t[r] > in.t.front())
        throw std::invalid_argument(fmt::format(
            "track '{}': a known start needs a ground-truth pose at its first odometry row (the first is at "
            "t = {} s, the odometry starts at {} s)",
            in.track_name, in.t[r], in.t.front()));
      return filters::PlanarPose{in.gt_x[r], in.gt_y[r], in.gt_theta[r]};
    }
  throw std::invalid_argument(fmt::format("track '{}': a known start needs a ground-truth pose; it has none",
                                          in.track_name));
}

}  // namespace

std::string_view to_string(OnlinePoseStart s) {
  switch (s) {
    case OnlinePoseStart::fixes: return "fixes";
    case OnlinePoseStart::known: return "known";
  }
  return "?";
}

bool parse_online_pose_start(std::string_view text, OnlinePoseStart* out) {
  return core::parse_by_name(text, kAllOnlinePoseStarts, out);
}

bool OnlinePoseOptions::IsValid(std::string* why) const {
  std::string sub;
  if (!filter.IsValid(&sub)) return core::invalid(why, "filter." + sub);
  if (!non_negative(known_start_sd_xy_m))
    return core::invalid(why, fmt::format("known_start_sd_xy_m = {} must be ≥ 0", known_start_sd_xy_m));
  if (!non_negative(known_start_sd_theta_rad))
    return core::invalid(why,
                         fmt::format("known_start_sd_theta_rad = {} must be ≥ 0", known_start_sd_theta_rad));
  if (min_memory_m && !(std::isfinite(*min_memory_m) && *min_memory_m > 0.0))
    return core::invalid(why, fmt::format("min_memory_m = {} must be > 0", *min_memory_m));
  if (!(std::isfinite(fix_sd_memory_factor) && fix_sd_memory_factor >= 0.0))
    return core::invalid(why, fmt::format("fix_sd_memory_factor = {} must be ≥ 0", fix_sd_memory_factor));
  if (fix_sd_m && !(std::isfinite(*fix_sd_m) && *fix_sd_m > 0.0))
    return core::invalid(why, fmt::format("fix_sd_m = {} must be > 0", *fix_sd_m));
  return true;
}

OnlinePoseTrack online_pose_track(const CalibrationInput& in, const OnlinePoseOptions& options) {
  if (in.fix_t.empty())
    throw std::invalid_argument(fmt::format(
        "track '{}': online-pose needs position fixes (aps_x, aps_y); `odotune fixes` makes them from ground "
        "truth",
        in.track_name));
  OnlinePoseTrack out;
  if (options.start == OnlinePoseStart::known) out.start_pose = known_start(in);
  const std::size_t n = in.t.size();
  std::size_t f = 0;
  auto add = [&](double t_s, double dt_s, double dphi_l, double dphi_r, bool with_fix) {
    filters::PoseCalibSample s{dt_s, dphi_l, dphi_r};
    if (with_fix) {
      const auto [vx, vy] = fix_variances(in, f, options);
      s.has_fix = true;
      s.fix_x_m = in.fix_x[f], s.fix_y_m = in.fix_y[f];
      s.fix_var_x_m2 = vx, s.fix_var_y_m2 = vy;
      ++f;
    }
    out.samples.push_back(s);
    out.t_s.push_back(t_s);
  };
  while (f < in.fix_t.size() && in.fix_t[f] <= in.t.front()) add(in.t.front(), 0.0, 0.0, 0.0, true);
  for (std::size_t r = 1; r < n; ++r) {
    const double t0 = in.t[r - 1], dt = in.t[r] - t0;
    const double phi_l = in.omega_l[r] * dt, phi_r = in.omega_r[r] * dt;
    double done = 0.0;  // fraction of the interval already sampled
    while (f < in.fix_t.size() && in.fix_t[f] <= in.t[r]) {
      const double frac = dt > 0.0 ? (in.fix_t[f] - t0) / dt : 1.0;
      const double part = frac - done;
      add(in.fix_t[f], part * dt, part * phi_l, part * phi_r, true);
      done = frac;
    }
    const double rest = 1.0 - done;
    if (rest > 0.0) add(in.t[r], rest * dt, rest * phi_l, rest * phi_r, false);
  }
  return out;
}

filters::DistanceMemoryParams online_pose_memory(const std::vector<const CalibrationInput*>& inputs,
                                                 const OnlinePoseOptions& options) {
  filters::DistanceMemoryParams m = options.filter.memory;
  if (options.min_memory_m) {
    m.min_memory_m = *options.min_memory_m;
  } else {
    std::vector<double> sd;
    for (const CalibrationInput* in : inputs)
      for (std::size_t i = 0; i < in->fix_t.size(); ++i) {
        const auto [vx, vy] = fix_variances(*in, i, options);
        sd.push_back(std::sqrt(0.5 * (vx + vy)));
      }
    if (!sd.empty())
      m.min_memory_m = std::max(m.min_memory_m, options.fix_sd_memory_factor * core::median(std::move(sd)));
  }
  m.max_memory_m = std::max(m.max_memory_m, m.min_memory_m);
  return m;
}

}  // namespace odotune::calibration
