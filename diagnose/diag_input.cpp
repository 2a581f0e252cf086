#include "diagnose/diag_input.h"

#include "diagnose/series_interp.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <initializer_list>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

namespace odotune::diagnose {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kMinSigmaM = 1e-3;     // floor of ref_sigma_m [m]
constexpr double kMinSigmaRad = 1e-3;   // floor of ref_sigma_rad [rad]
constexpr double kMadToSigma = 1.4826;  // sigma = 1.4826*MAD for a normal distribution

[[noreturn]] void fail(const Track& track, const std::string& what) {
  throw std::invalid_argument(fmt::format("track '{}': {}", track.name(), what));
}

// A finite number >= 0 from metadata key `key`, if present and well-formed.
std::optional<double> meta_number(const Track& track, std::string_view key) {
  const auto text = track.meta().get(key);
  if (!text) return std::nullopt;
  double v = 0.0;
  const char* end = text->data() + text->size();
  const auto [p, ec] = std::from_chars(text->data(), end, v);
  if (ec != std::errc() || p != end || !std::isfinite(v) || v < 0.0) return std::nullopt;
  return v;
}

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  double m = *mid;
  if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), mid));
  return m;
}

// Robust standard deviation of a sample: 1.4826*median(|v - median(v)|).
double robust_sigma(const std::vector<double>& v) {
  const double m = median(v);
  std::vector<double> dev(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) dev[i] = std::abs(v[i] - m);
  return kMadToSigma * median(std::move(dev));
}

void fill_odometry(const Track& track, DiagInput& in) {
  const auto& t = track.t();
  const auto& meta = track.meta();
  const bool wheels = track.has_ticks() || track.has_wheel_rates();
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
  }

  if (track.has_ticks()) {
    if (!meta.ticks_per_rev || !(*meta.ticks_per_rev > 0))
      fail(track, "tick columns need robot.ticks_per_rev > 0 in the metadata");
    const double per_tick = kTwoPi / *meta.ticks_per_rev;
    const auto& tl = track.ticks_l();
    const auto& tr = track.ticks_r();
    std::int64_t l0 = 0, r0 = 0;
    for (std::size_t i = 0; i < t.size(); ++i) {
      if (tl[i] == kNoTick || tr[i] == kNoTick) continue;
      if (in.odo_t_s.empty()) l0 = tl[i], r0 = tr[i];
      in.odo_t_s.push_back(t[i]);
      in.phi_l_rad.push_back(static_cast<double>(tl[i] - l0) * per_tick);
      in.phi_r_rad.push_back(static_cast<double>(tr[i] - r0) * per_tick);
    }
  } else if (track.has_wheel_rates()) {
    double pl = 0.0, pr = 0.0, ol = 0.0, orr = 0.0;
    for (std::size_t i = 0; i < t.size(); ++i) {
      if (!track.at(Col::omega_l, i) || !track.at(Col::omega_r, i)) continue;
      const double wl = track.col(Col::omega_l)[i], wr = track.col(Col::omega_r)[i];
      if (!in.odo_t_s.empty()) {
        const double h = t[i] - in.odo_t_s.back();
        pl += 0.5 * (ol + wl) * h;
        pr += 0.5 * (orr + wr) * h;
      }
      ol = wl, orr = wr;
      in.odo_t_s.push_back(t[i]);
      in.phi_l_rad.push_back(pl);
      in.phi_r_rad.push_back(pr);
    }
  }
  if (track.has_cmd()) {
    std::vector<double> ct, cv, cw;
    for (std::size_t i = 0; i < t.size(); ++i) {
      if (!track.at(Col::v_cmd, i) || !track.at(Col::w_cmd, i)) continue;
      ct.push_back(t[i]);
      cv.push_back(track.col(Col::v_cmd)[i]);
      cw.push_back(track.col(Col::w_cmd)[i]);
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
  if (in.odo_t_s.size() < 2)
    fail(track, "no usable odometry; expected at least 2 rows with ticks_l and ticks_r, "
                "omega_l and omega_r, or v_cmd and w_cmd");
}

void fill_reference(const Track& track, DiagInput& in) {
  const auto& t = track.t();
  const double t_lo = in.odo_t_s.front(), t_hi = in.odo_t_s.back();
  const bool gt = track.has_gt();
  if (!gt && !track.has_aps())
    fail(track, "no reference; expected gt_x, gt_y (ground truth) or aps_x, aps_y (fixes)");
  const Col cx = gt ? Col::gt_x : Col::aps_x, cy = gt ? Col::gt_y : Col::aps_y;
  bool heading = gt && track.has(Col::gt_theta);
  std::vector<double> theta;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (!track.at(cx, i) || !track.at(cy, i) || t[i] < t_lo || t[i] > t_hi) continue;
    in.ref_t_s.push_back(t[i]);
    in.ref_x_m.push_back(track.col(cx)[i]);
    in.ref_y_m.push_back(track.col(cy)[i]);
    if (heading) {
      if (track.at(Col::gt_theta, i))
        theta.push_back(track.col(Col::gt_theta)[i]);
      else
        heading = false;
    }
  }
  in.reference = gt ? ReferenceKind::gt : ReferenceKind::aps;
  const std::size_t need = heading ? 2 : 3;
  if (in.ref_t_s.size() < need)
    fail(track, fmt::format("{} {} sample(s) within the odometry's time span [{}, {}] s; expected "
                            "at least {}",
                            in.ref_t_s.size(), gt ? "ground-truth" : "position-fix", t_lo, t_hi, need));
  if (heading) {  // unwrap
    in.ref_theta_rad.resize(theta.size());
    double offset = 0.0;
    for (std::size_t i = 0; i < theta.size(); ++i) {
      if (i > 0) {
        const double d = theta[i] + offset - in.ref_theta_rad[i - 1];
        offset -= kTwoPi * std::round(d / kTwoPi);
      }
      in.ref_theta_rad[i] = theta[i] + offset;
    }
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

// Estimates the sigmas that are NaN (not stated), then applies the floors.
void estimate_sigmas(DiagInput& in) {
  const NominalPath p = nominal_path(in);
  const std::size_t m = in.ref_t_s.size();
  std::vector<double> ox(m), oy(m), oth(m);
  for (std::size_t i = 0; i < m; ++i) {
    ox[i] = interp_held(in.odo_t_s, p.x, in.ref_t_s[i]);
    oy[i] = interp_held(in.odo_t_s, p.y, in.ref_t_s[i]);
    oth[i] = interp_held(in.odo_t_s, p.th, in.ref_t_s[i]);
  }
  if (std::isnan(in.ref_sigma_m)) {
    std::vector<double> chord(m - 1), diff(m - 1);
    for (std::size_t i = 0; i + 1 < m; ++i) {
      chord[i] = std::hypot(ox[i + 1] - ox[i], oy[i + 1] - oy[i]);
      diff[i] = std::hypot(in.ref_x_m[i + 1] - in.ref_x_m[i], in.ref_y_m[i + 1] - in.ref_y_m[i]) - chord[i];
    }
    auto sigma_above = [&](double min_chord) {
      std::vector<double> d;
      for (std::size_t i = 0; i < diff.size(); ++i)
        if (chord[i] > min_chord) d.push_back(diff[i]);
      return std::pair{d.size(), d.size() >= 3 ? robust_sigma(d) / std::sqrt(2.0) : 0.0};
    };
    auto [n0, s0] = sigma_above(0.0);
    const auto [n1, s1] = sigma_above(3.0 * s0);
    if (n1 >= 10) s0 = s1;
    in.ref_sigma_m = n0 >= 3 ? s0 : 0.0;
  }
  in.ref_sigma_m = std::max(in.ref_sigma_m, kMinSigmaM);
  if (!in.has_ref_heading()) {
    in.ref_sigma_rad = std::nan("");
    return;
  }
  if (std::isnan(in.ref_sigma_rad)) {
    std::vector<double> d(m - 1);
    for (std::size_t i = 0; i + 1 < m; ++i)
      d[i] = (in.ref_theta_rad[i + 1] - in.ref_theta_rad[i]) - (oth[i + 1] - oth[i]);
    in.ref_sigma_rad = d.size() >= 3 ? robust_sigma(d) / std::sqrt(2.0) : 0.0;
  }
  in.ref_sigma_rad = std::max(in.ref_sigma_rad, kMinSigmaRad);
}

}  // namespace

DiagInput build_diag_input(const Track& track) {
  if (!track.has_odometry())
    fail(track, "no odometry; expected ticks_l/ticks_r, omega_l/omega_r or v_cmd/w_cmd columns");
  DiagInput in;
  in.track_name = track.name();
  fill_odometry(track, in);
  if (track.has(Col::gyro_z))
    for (std::size_t i = 0; i < track.size(); ++i)
      if (track.at(Col::gyro_z, i)) {
        in.gyro_t_s.push_back(track.t()[i]);
        in.gyro_z_radps.push_back(track.col(Col::gyro_z)[i]);
      }
  fill_reference(track, in);
  const bool gt = in.reference == ReferenceKind::gt;
  // NaN = not stated: estimate_sigmas() estimates it.
  const double nan = std::nan("");
  in.ref_sigma_m = meta_number(track, gt ? "sim.gt_sigma_m" : "sim.aps_sigma_m").value_or(nan);
  in.ref_sigma_rad = gt ? meta_number(track, "sim.gt_sigma_rad").value_or(nan) : nan;
  estimate_sigmas(in);
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
  keep_between(c.odo_t_s, {&c.phi_l_rad, &c.phi_r_rad, &c.v_mps, &c.w_radps, &c.cmd_v_mps, &c.cmd_w_radps},
               t0_s, t1_s);
  keep_between(c.gyro_t_s, {&c.gyro_z_radps}, t0_s, t1_s);
  keep_between(c.ref_t_s, {&c.ref_x_m, &c.ref_y_m, &c.ref_theta_rad}, t0_s, t1_s);
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
