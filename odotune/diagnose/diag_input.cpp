#include <odotune/diagnose/diag_input.h>

#include <odotune/core/robust_stats.h>

#include <odotune/diagnose/series_interp.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

namespace odotune::diagnose {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kMinSigmaM = 1e-3;    // floor of ref_sigma_m [m]
constexpr double kMinSigmaRad = 1e-3;  // floor of ref_sigma_rad [rad]

[[noreturn]] void fail(const tracks::Track& track, const std::string& what) {
  throw std::invalid_argument(fmt::format("track '{}': {}", track.name(), what));
}

// A finite number >= 0 from metadata key `key`, if present and well-formed.
std::optional<double> meta_number(const tracks::Track& track, std::string_view key) {
  const auto text = track.meta().get(key);
  if (!text) return std::nullopt;
  double v = 0.0;
  const char* end = text->data() + text->size();
  const auto [p, ec] = std::from_chars(text->data(), end, v);
  if (ec != std::errc() || p != end || !std::isfinite(v) || v < 0.0) return std::nullopt;
  return v;
}

// The robot's nominal kinematics and the odometry's kind: wheel angles
// (which need the radii and wheel base) or body velocities (commanded, or
// measured as the source note says).
void fill_kinematics(const tracks::Track& track, bool wheels, DiagInput& in) {
  const auto& meta = track.meta();
  if (wheels) {
    if (!meta.wheel_radius_left_m || !meta.wheel_radius_right_m || !meta.wheel_base_m)
      fail(track, "wheel odometry needs robot.wheel_radius_left, robot.wheel_radius_right and "
                  "robot.wheel_base in the metadata");
    in.radius_l_m = *meta.wheel_radius_left_m;
    in.radius_r_m = *meta.wheel_radius_right_m;
    in.wheel_base_m = *meta.wheel_base_m;
    if (!(in.radius_l_m > 0 && in.radius_r_m > 0 && in.wheel_base_m > 0))
      fail(track, fmt::format("nominal robot radii {} m, {} m and base {} m; expected all > 0", in.radius_l_m,
                              in.radius_r_m, in.wheel_base_m));
    in.odometry = OdometryKind::wheel_angles;
  } else {
    in.radius_l_m = meta.wheel_radius_left_m.value_or(0.0);
    in.radius_r_m = meta.wheel_radius_right_m.value_or(0.0);
    in.wheel_base_m = meta.wheel_base_m.value_or(0.0);
    in.odometry = OdometryKind::body_velocity;
    const auto note = track.meta().get("source.note");
    const bool measured = note &&
                          (note->find("measured") != std::string::npos ||
                           note->find("not commands") != std::string::npos) &&
                          note->find("not measured") == std::string::npos;
    in.velocity_source = measured ? "velocity odometry" : "command";
  }
}

// The wheel angles from the first tick counts on, or integrated from the
// wheel rates (trapezoids); nothing when the track has neither.
void fill_wheel_angles(const tracks::Track& track, DiagInput& in) {
  const auto& t = track.t();
  const auto& meta = track.meta();
  if (track.has_ticks()) {
    if (!meta.ticks_per_rev || !(*meta.ticks_per_rev > 0))
      fail(track, "tick columns need robot.ticks_per_rev > 0 in the metadata");
    const double per_tick = kTwoPi / *meta.ticks_per_rev;
    const auto& tl = track.ticks_l();
    const auto& tr = track.ticks_r();
    std::int64_t l0 = 0, r0 = 0;
    for (std::size_t i = 0; i < t.size(); ++i) {
      if (tl[i] == tracks::kNoTick || tr[i] == tracks::kNoTick) continue;
      if (in.odo_t_s.empty()) {
        l0 = tl[i];
        r0 = tr[i];
      }
      in.odo_t_s.push_back(t[i]);
      in.phi_l_rad.push_back(static_cast<double>(tl[i] - l0) * per_tick);
      in.phi_r_rad.push_back(static_cast<double>(tr[i] - r0) * per_tick);
    }
  } else if (track.has_wheel_rates()) {
    double pl = 0.0, pr = 0.0, ol = 0.0, orr = 0.0;
    for (std::size_t i = 0; i < t.size(); ++i) {
      if (!track.at(tracks::Col::omega_l, i) || !track.at(tracks::Col::omega_r, i)) continue;
      const double wl = track.col(tracks::Col::omega_l)[i], wr = track.col(tracks::Col::omega_r)[i];
      if (!in.odo_t_s.empty()) {
        const double h = t[i] - in.odo_t_s.back();
        pl += 0.5 * (ol + wl) * h;
        pr += 0.5 * (orr + wr) * h;
      }
      ol = wl;
      orr = wr;
      in.odo_t_s.push_back(t[i]);
      in.phi_l_rad.push_back(pl);
      in.phi_r_rad.push_back(pr);
    }
  }
}

// The commands: the odometry itself without wheels, else held at each
// odometry time.
void fill_commands(const tracks::Track& track, bool wheels, DiagInput& in) {
  const auto& t = track.t();
  std::vector<double> ct, cv, cw;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (!track.at(tracks::Col::v_cmd, i) || !track.at(tracks::Col::w_cmd, i)) continue;
    ct.push_back(t[i]);
    cv.push_back(track.col(tracks::Col::v_cmd)[i]);
    cw.push_back(track.col(tracks::Col::w_cmd)[i]);
  }
  if (!wheels) {
    in.odo_t_s = std::move(ct);
    in.v_mps = std::move(cv);
    in.w_radps = std::move(cw);
  } else if (!ct.empty()) {
    in.cmd_v_mps.reserve(in.odo_t_s.size());
    in.cmd_w_radps.reserve(in.odo_t_s.size());
    for (double x : in.odo_t_s) {
      in.cmd_v_mps.push_back(interp_held(ct, cv, x));
      in.cmd_w_radps.push_back(interp_held(ct, cw, x));
    }
  }
}

void fill_odometry(const tracks::Track& track, DiagInput& in) {
  const bool wheels = track.has_ticks() || track.has_wheel_rates();
  fill_kinematics(track, wheels, in);
  fill_wheel_angles(track, in);
  if (track.has_cmd()) fill_commands(track, wheels, in);
  if (in.odo_t_s.size() < 2)
    fail(track, "no usable odometry; expected at least 2 rows with ticks_l and ticks_r, "
                "omega_l and omega_r, or v_cmd and w_cmd");
}

// One source of reference samples (ground truth or fixes) within the odometry's span.
struct RefSource {
  std::vector<double> t, x, y, theta;  // theta: only when every sample has it
  bool heading = false;
  double sigma_m = 0.0, sigma_rad = 0.0;  // NaN = not stated (estimated later)
};

RefSource read_source(const tracks::Track& track, tracks::Col cx, tracks::Col cy, bool with_heading,
                      double t_lo, double t_hi) {
  RefSource s;
  const auto& t = track.t();
  s.heading = with_heading;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (!track.at(cx, i) || !track.at(cy, i) || t[i] < t_lo || t[i] > t_hi) continue;
    s.t.push_back(t[i]);
    s.x.push_back(track.col(cx)[i]);
    s.y.push_back(track.col(cy)[i]);
    if (s.heading) {
      if (track.at(tracks::Col::gt_theta, i))
        s.theta.push_back(track.col(tracks::Col::gt_theta)[i]);
      else
        s.heading = false;
    }
  }
  if (!s.heading) s.theta.clear();
  return s;
}

// Median interval between consecutive samples [s]; +inf with fewer than 2.
double median_interval(const std::vector<double>& t) {
  return t.size() < 2 ? std::numeric_limits<double>::infinity() : core::median_period_s(t);
}

// Fixes that ground truth does not already cover: those with no ground-truth
// sample within 1.5 of its median intervals (header comment).
RefSource uncovered(const RefSource& fixes, const RefSource& gt) {
  const double reach = 1.5 * median_interval(gt.t);
  RefSource out;
  out.sigma_m = fixes.sigma_m;
  for (std::size_t i = 0; i < fixes.t.size(); ++i) {
    const auto it = std::lower_bound(gt.t.begin(), gt.t.end(), fixes.t[i]);
    double gap = std::numeric_limits<double>::infinity();
    if (it != gt.t.end()) gap = *it - fixes.t[i];
    if (it != gt.t.begin()) gap = std::min(gap, fixes.t[i] - *(it - 1));
    if (gap < 1e-9 || (std::isfinite(reach) && gap <= reach)) continue;
    out.t.push_back(fixes.t[i]);
    out.x.push_back(fixes.x[i]);
    out.y.push_back(fixes.y[i]);
  }
  return out;
}

// Unwraps headings in place: each step brought within pi of the heading
// change `predicted(t_prev, t_next)` that the robot's own sensors show over it
// (the gyro's integral where it covers the step, else the nominal odometry's).
// Between densely sampled headings the prediction hardly matters (a step
// turns far less than pi); across a gap of the reference it decides: a robot
// that turned 5 rad during a 10 s gap must not come out 2 pi short, or every
// heading after the gap (window residuals, the sensor checks' bins across the
// gap) is off by a whole turn.
template <class Predict>
void unwrap(const std::vector<double>& t, std::vector<double>& theta, Predict predicted) {
  double offset = 0.0, prev = 0.0;
  for (std::size_t i = 0; i < theta.size(); ++i) {
    const double raw = theta[i];
    if (i > 0) offset -= kTwoPi * std::round((raw + offset - prev - predicted(t[i - 1], t[i])) / kTwoPi);
    theta[i] = prev = raw + offset;
  }
}

// Nominal dead reckoning (track-format.md kinematics, arc update) at the
// odometry samples: x, y, theta per node.
struct NominalPath {
  std::vector<double> x, y, th;
};
NominalPath nominal_path(const DiagInput& in) {
  const std::size_t n = in.odo_t_s.size();
  NominalPath p{std::vector<double>(n, 0.0), std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)};
  const bool wheels = in.odometry == OdometryKind::wheel_angles;
  for (std::size_t k = 0; k + 1 < n; ++k) {
    double ds = 0.0, dth = 0.0;
    if (wheels) {
      const double dl = in.radius_l_m * (in.phi_l_rad[k + 1] - in.phi_l_rad[k]);
      const double dr = in.radius_r_m * (in.phi_r_rad[k + 1] - in.phi_r_rad[k]);
      ds = 0.5 * (dl + dr);
      dth = (dr - dl) / in.wheel_base_m;
    } else {
      const double h = in.odo_t_s[k + 1] - in.odo_t_s[k];
      ds = 0.5 * (in.v_mps[k] + in.v_mps[k + 1]) * h;
      dth = 0.5 * (in.w_radps[k] + in.w_radps[k + 1]) * h;
    }
    const double half = 0.5 * dth;
    const double sc = std::abs(half) < 1e-4 ? 1.0 - half * half / 6.0 : std::sin(half) / half;
    const double thm = p.th[k] + half;
    p.x[k + 1] = p.x[k] + sc * ds * std::cos(thm);
    p.y[k + 1] = p.y[k] + sc * ds * std::sin(thm);
    p.th[k + 1] = p.th[k] + dth;
  }
  return p;
}

// Estimates the sigmas of `s` that are NaN (not stated) from its own samples
// (header comment); leaves them NaN with fewer than 3 samples.
void estimate_sigmas(const DiagInput& in, const NominalPath& p, RefSource& s) {
  const std::size_t m = s.t.size();
  if (m < 3) return;
  std::vector<double> ox(m), oy(m), oth(m);
  for (std::size_t i = 0; i < m; ++i) {
    ox[i] = interp_held(in.odo_t_s, p.x, s.t[i]);
    oy[i] = interp_held(in.odo_t_s, p.y, s.t[i]);
    oth[i] = interp_held(in.odo_t_s, p.th, s.t[i]);
  }
  if (std::isnan(s.sigma_m)) {
    std::vector<double> chord(m - 1), diff(m - 1);
    for (std::size_t i = 0; i + 1 < m; ++i) {
      chord[i] = std::hypot(ox[i + 1] - ox[i], oy[i + 1] - oy[i]);
      diff[i] = std::hypot(s.x[i + 1] - s.x[i], s.y[i + 1] - s.y[i]) - chord[i];
    }
    auto sigma_above = [&](double min_chord) {
      std::vector<double> d;
      for (std::size_t i = 0; i < diff.size(); ++i)
        if (chord[i] > min_chord) d.push_back(diff[i]);
      return std::pair{d.size(), d.size() >= 3 ? core::robust_sigma(d) / std::sqrt(2.0) : 0.0};
    };
    auto [n0, s0] = sigma_above(0.0);
    const auto [n1, s1] = sigma_above(3.0 * s0);
    if (n1 >= 10) s0 = s1;
    s.sigma_m = n0 >= 3 ? s0 : 0.0;
  }
  if (s.heading && std::isnan(s.sigma_rad)) {
    std::vector<double> d(m - 1);
    for (std::size_t i = 0; i + 1 < m; ++i) d[i] = (s.theta[i + 1] - s.theta[i]) - (oth[i + 1] - oth[i]);
    s.sigma_rad = core::robust_sigma(d) / std::sqrt(2.0);
  }
}

// Lays the sources out as the input's reference (header comment, "Reference").
void assemble_reference(RefSource gt, RefSource fixes, DiagInput& in) {
  const NominalPath p = nominal_path(in);
  if (gt.heading) {
    const bool gyro = in.gyro_t_s.size() >= 2;
    const Cumulative g = gyro ? Cumulative::of_rates(in.gyro_t_s, in.gyro_z_radps) : Cumulative{};
    unwrap(gt.t, gt.theta, [&](double t0, double t1) {
      if (gyro && t0 >= g.front_t() && t1 <= g.back_t()) return g.at(t1) - g.at(t0);
      return interp_held(in.odo_t_s, p.th, t1) - interp_held(in.odo_t_s, p.th, t0);
    });
  }
  estimate_sigmas(in, p, gt);
  estimate_sigmas(in, p, fixes);
  // A source too small to estimate its own noise borrows the other's.
  if (std::isnan(gt.sigma_m)) gt.sigma_m = fixes.sigma_m;
  if (std::isnan(fixes.sigma_m)) fixes.sigma_m = gt.sigma_m;
  const double sigma_gt = std::max(std::isnan(gt.sigma_m) ? 0.0 : gt.sigma_m, kMinSigmaM);
  const double sigma_fix = std::max(std::isnan(fixes.sigma_m) ? 0.0 : fixes.sigma_m, kMinSigmaM);
  in.ref_gt_samples = gt.t.size();
  in.ref_fix_samples = fixes.t.size();
  in.reference = gt.t.size() >= fixes.t.size() ? ReferenceKind::gt : ReferenceKind::aps;
  in.ref_sigma_m = in.reference == ReferenceKind::gt ? sigma_gt : sigma_fix;
  in.ref_sigma_rad = std::nan("");
  if (fixes.t.empty()) {
    in.ref_t_s = std::move(gt.t);
    in.ref_x_m = std::move(gt.x);
    in.ref_y_m = std::move(gt.y);
    if (gt.heading) {
      in.ref_theta_rad = std::move(gt.theta);
      in.ref_sigma_rad = std::max(std::isnan(gt.sigma_rad) ? 0.0 : gt.sigma_rad, kMinSigmaRad);
    }
    return;
  }
  if (gt.t.empty()) {
    in.ref_t_s = std::move(fixes.t);
    in.ref_x_m = std::move(fixes.x);
    in.ref_y_m = std::move(fixes.y);
    return;
  }
  // Mixed: positions of both sources in time order, each weighted by its own
  // noise against ref_sigma_m; headings unused (fixes carry none).
  const double w_gt = (in.ref_sigma_m / sigma_gt) * (in.ref_sigma_m / sigma_gt);
  const double w_fix = (in.ref_sigma_m / sigma_fix) * (in.ref_sigma_m / sigma_fix);
  std::size_t a = 0, b = 0;
  while (a < gt.t.size() || b < fixes.t.size()) {
    const bool take_gt = b >= fixes.t.size() || (a < gt.t.size() && gt.t[a] <= fixes.t[b]);
    const RefSource& s = take_gt ? gt : fixes;
    const std::size_t i = take_gt ? a++ : b++;
    in.ref_t_s.push_back(s.t[i]);
    in.ref_x_m.push_back(s.x[i]);
    in.ref_y_m.push_back(s.y[i]);
    in.ref_w.push_back(take_gt ? w_gt : w_fix);
  }
}

}  // namespace

DiagInput build_diag_input(const tracks::Track& track) {
  if (!track.has_odometry())
    fail(track, "no odometry; expected ticks_l/ticks_r, omega_l/omega_r or v_cmd/w_cmd columns");
  DiagInput in;
  in.track_name = track.name();
  fill_odometry(track, in);
  if (track.has(tracks::Col::gyro_z))
    for (std::size_t i = 0; i < track.size(); ++i)
      if (track.at(tracks::Col::gyro_z, i)) {
        in.gyro_t_s.push_back(track.t()[i]);
        in.gyro_z_radps.push_back(track.col(tracks::Col::gyro_z)[i]);
      }
  if (!track.has_gt() && !track.has_aps())
    fail(track, "no reference; expected gt_x, gt_y (ground truth) or aps_x, aps_y (position fixes)");
  const double t_lo = in.odo_t_s.front(), t_hi = in.odo_t_s.back();
  RefSource gt, fixes;
  // NaN = not stated: estimate_sigmas() estimates it.
  const double nan = std::nan("");
  if (track.has_gt()) {
    gt = read_source(track, tracks::Col::gt_x, tracks::Col::gt_y, track.has(tracks::Col::gt_theta), t_lo, t_hi);
    gt.sigma_m = meta_number(track, "sim.gt_sigma_m").value_or(nan);
    gt.sigma_rad = meta_number(track, "sim.gt_sigma_rad").value_or(nan);
  }
  if (track.has_aps()) {
    fixes = uncovered(read_source(track, tracks::Col::aps_x, tracks::Col::aps_y, false, t_lo, t_hi), gt);
    fixes.sigma_m = meta_number(track, "sim.aps_sigma_m").value_or(nan);
  }
  if (gt.t.empty() && fixes.t.empty())
    fail(track, fmt::format("no reference sample within the odometry's time span [{}, {}] s; expected ground "
                            "truth (gt_x, gt_y) or position fixes (aps_x, aps_y) there",
                            t_lo, t_hi));
  assemble_reference(std::move(gt), std::move(fixes), in);
  return in;
}

namespace {
// Keeps the entries i of each array in `cols` for which keep(t[i]).
void keep_between(std::vector<double>& t, std::initializer_list<std::vector<double>*> cols, double t0,
                  double t1) {
  std::size_t out = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] < t0 || t[i] > t1) continue;
    for (std::vector<double>* c : cols)
      if (!c->empty()) (*c)[out] = (*c)[i];
    t[out++] = t[i];
  }
  t.resize(out);
  for (std::vector<double>* c : cols)
    if (!c->empty()) c->resize(out);
}
}  // namespace

DiagInput crop(const DiagInput& in, double t0_s, double t1_s) {
  if (!(t0_s < t1_s))
    throw std::invalid_argument(fmt::format("{}: empty time range [{}, {}] s", in.track_name, t0_s, t1_s));
  DiagInput c = in;
  c.fixed_window_starts_s.clear();
  keep_between(c.odo_t_s, {&c.phi_l_rad, &c.phi_r_rad, &c.v_mps, &c.w_radps, &c.cmd_v_mps, &c.cmd_w_radps},
               t0_s, t1_s);
  keep_between(c.gyro_t_s, {&c.gyro_z_radps}, t0_s, t1_s);
  keep_between(c.ref_t_s, {&c.ref_x_m, &c.ref_y_m, &c.ref_theta_rad, &c.ref_w}, t0_s, t1_s);
  if (c.odo_t_s.size() < 2 || c.ref_t_s.size() < 2)
    throw std::invalid_argument(fmt::format(
        "{}: the range [{}, {}] s holds {} odometry and {} reference samples; expected at least 2 of each",
        in.track_name, t0_s, t1_s, c.odo_t_s.size(), c.ref_t_s.size()));
  if (!c.phi_l_rad.empty()) {
    const double l0 = c.phi_l_rad.front(), r0 = c.phi_r_rad.front();
    for (double& v : c.phi_l_rad) v -= l0;
    for (double& v : c.phi_r_rad) v -= r0;
  }
  return c;
}

}  // namespace odotune::diagnose
