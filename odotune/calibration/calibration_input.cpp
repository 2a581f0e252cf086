#include <odotune/calibration/calibration_input.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string_view>

#include <fmt/format.h>

#include <odotune/calibration/reference_jitter.h>
#include <odotune/core/why.h>
#include <odotune/objectives/pose_series.h>
#include <odotune/objectives/track_samples.h>
#include <odotune/sim/effects.h>

namespace odotune::calibration {

namespace {

// Upper bound of ext_from_gt_rate_hz [Hz] (beyond any ground-truth rate; keeps
// the sample count bounded).
constexpr double kMaxExtFromGtRateHz = 1000.0;
// Time stamps closer than this are the same instant [s] (k/f against a row
// stamp written with a few decimals).
constexpr double kSameInstantS = 1e-6;

[[noreturn]] void fail(const std::string& track, const std::string& what) {
  throw std::invalid_argument(fmt::format("track '{}': {}", track, what));
}

std::string_view trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

// The robot's nominal geometry from the metadata into in.nominal; returns
// ticks_per_rev (0 without ticks).
double read_nominal(const tracks::Track& track, bool from_ticks, CalibrationInput& in) {
  const std::string& name = track.name();
  std::string why;
  const tracks::TrackMeta& meta = track.meta();
  auto require = [&](const std::optional<double>& v, const char* key) {
    if (!v)
      fail(name, fmt::format("metadata '{}' is missing: calibration needs the robot's nominal "
                             "wheel radii, wheel base{}",
                             key, from_ticks ? " and ticks_per_rev" : ""));
    return *v;
  };
  in.nominal.wheel_radius_left_m = require(meta.wheel_radius_left_m, "robot.wheel_radius_left");
  in.nominal.wheel_radius_right_m = require(meta.wheel_radius_right_m, "robot.wheel_radius_right");
  in.nominal.wheel_base_m = require(meta.wheel_base_m, "robot.wheel_base");
  const double ticks_per_rev = from_ticks ? require(meta.ticks_per_rev, "robot.ticks_per_rev") : 0.0;
  if (!in.nominal.IsValid(&why)) fail(name, "nominal robot metadata: " + why);
  if (from_ticks && !(std::isfinite(ticks_per_rev) && ticks_per_rev > 0.0))
    fail(name, fmt::format("robot.ticks_per_rev = {} must be a finite number > 0", ticks_per_rev));
  return ticks_per_rev;
}

// The odometry rows: their times and wheel rates into `in` (from ticks, the
// rate over the interval ending at the row); returns each one's track row.
std::vector<std::size_t> read_odometry_rows(const tracks::Track& track, bool from_ticks, double ticks_per_rev,
                                            CalibrationInput& in) {
  const auto& t = track.t();
  std::vector<std::size_t> track_row;  // per odometry row: its row in the track
  for (std::size_t i = 0; i < track.size(); ++i) {
    const bool odo = from_ticks ? track.ticks_l()[i] != tracks::kNoTick && track.ticks_r()[i] != tracks::kNoTick
                                : track.at(tracks::Col::omega_l, i) && track.at(tracks::Col::omega_r, i);
    if (!odo) continue;
    double wl = 0.0, wr = 0.0;
    if (from_ticks) {
      if (!track_row.empty()) {
        const std::size_t p = track_row.back();
        const double k = 2.0 * std::numbers::pi / ticks_per_rev / (t[i] - t[p]);
        wl = static_cast<double>(track.ticks_l()[i] - track.ticks_l()[p]) * k;
        wr = static_cast<double>(track.ticks_r()[i] - track.ticks_r()[p]) * k;
      }
    } else {
      wl = track.col(tracks::Col::omega_l)[i];
      wr = track.col(tracks::Col::omega_r)[i];
    }
    track_row.push_back(i);
    in.t.push_back(t[i]);
    in.omega_l.push_back(wl);
    in.omega_r.push_back(wr);
  }
  return track_row;
}

// The ground-truth pose at each odometry row (NaN where none within kMaxGtGapS).
void ground_truth_at_rows(const objectives::PoseSeries& gt, CalibrationInput& in) {
  const std::size_t n_rows = in.t.size();
  in.gt_x.assign(n_rows, std::nan(""));
  in.gt_y.assign(n_rows, std::nan(""));
  in.gt_theta.assign(n_rows, std::nan(""));
  for (std::size_t r = 0; r < n_rows; ++r) {
    const auto p = objectives::interpolate_pose(gt, in.t[r], objectives::kMaxGtGapS);
    if (!p) continue;
    in.gt_x[r] = p->x_m;
    in.gt_y[r] = p->y_m;
    in.gt_theta[r] = p->theta_rad;
  }
}

// Adds calibration samples to `in`, each with the wheel rates at its
// odometry row (or their mean over the window centred on it).
class SampleAdder {
 public:
  SampleAdder(CalibrationInput& in, const CalibrationInputOptions& options, bool from_ticks)
      : in_(in), options_(options), n_rows_(in.t.size()), angle_l_(n_rows_, 0.0), angle_r_(n_rows_, 0.0) {
    // Wheel angle turned since the first odometry row [rad]: exact from ticks
    // (the interval rates times their intervals), trapezoidal from omega samples.
    for (std::size_t r = 1; r < n_rows_; ++r) {
      const double dt = in.t[r] - in.t[r - 1];
      const double wl = from_ticks ? in.omega_l[r] : 0.5 * (in.omega_l[r] + in.omega_l[r - 1]);
      const double wr = from_ticks ? in.omega_r[r] : 0.5 * (in.omega_r[r] + in.omega_r[r - 1]);
      angle_l_[r] = angle_l_[r - 1] + wl * dt;
      angle_r_[r] = angle_r_[r - 1] + wr * dt;
    }
  }

  std::size_t n_rows() const { return n_rows_; }

  // The odometry row at or before time t_s (n_rows when none).
  std::size_t row_at(double t_s) const {
    const auto it = std::upper_bound(in_.t.begin(), in_.t.end(), t_s);
    return it == in_.t.begin() ? n_rows_ : static_cast<std::size_t>(it - in_.t.begin()) - 1;
  }

  void add(double t_s, std::size_t row, filters::CalibSample s) {
    s.dt_s = in_.sample_t.empty() ? 0.0 : t_s - in_.sample_t.back();
    s.omega_l_rad_s = in_.omega_l[row];
    s.omega_r_rad_s = in_.omega_r[row];
    // The mean rate over the window centred on the measurement, when the
    // window spans at least one whole odometry interval.
    const double half_window = 0.5 * options_.wheel_rate_window_s;
    if (half_window > 0.0) {
      const std::size_t a = row_at(t_s - half_window + kSameInstantS);
      const std::size_t b = row_at(t_s + half_window + kSameInstantS);
      if (a != n_rows_ && b != n_rows_ && b > a) {
        const double span = in_.t[b] - in_.t[a];
        s.omega_l_rad_s = (angle_l_[b] - angle_l_[a]) / span;
        s.omega_r_rad_s = (angle_r_[b] - angle_r_[a]) / span;
      }
    }
    in_.samples.push_back(s);
    in_.sample_row.push_back(row);
    in_.sample_t.push_back(t_s);
  }

 private:
  CalibrationInput& in_;
  const CalibrationInputOptions& options_;
  std::size_t n_rows_;
  std::vector<double> angle_l_, angle_r_;
};

// The variances of velocities derived from the ground truth at `rate` Hz
// (from its jitter and the encoders' quantisation, or as given), with the
// note in in.ext_noise.
std::pair<double, double> derived_variances(const objectives::PoseSeries& gt,
                                            const CalibrationInputOptions& options, bool from_ticks,
                                            double ticks_per_rev, CalibrationInput& in) {
  const double rate = options.ext_from_gt_rate_hz;
  const double period = 1.0 / rate;
  double v_var = options.default_v_var, w_var = options.default_w_var;
  if (options.estimate_ext_noise) {
    const ReferenceJitter j = estimate_reference_jitter(gt);
    double enc_v = 0.0, enc_w = 0.0;  // encoder quantisation variances (header)
    if (from_ticks && options.wheel_rate_window_s > 0.0) {
      const double q = 2.0 * std::numbers::pi / ticks_per_rev / options.wheel_rate_window_s;
      const double var_omega = q * q / 6.0;
      const double r = 0.5 * (in.nominal.wheel_radius_left_m + in.nominal.wheel_radius_right_m);
      enc_v = r * r * var_omega / 2.0;
      enc_w = 2.0 * r * r * var_omega / (in.nominal.wheel_base_m * in.nominal.wheel_base_m);
    }
    v_var = 2.0 * j.sigma_xy_m * j.sigma_xy_m / (period * period) + enc_v;
    w_var = 2.0 * j.sigma_theta_rad * j.sigma_theta_rad / (period * period) + enc_w;
    if (!(v_var > 0.0)) v_var = options.default_v_var;  // an exact reference without ticks
    if (!(w_var > 0.0)) w_var = options.default_w_var;
    in.ext_noise = fmt::format(
        "derived from the ground truth at {:g} Hz; sigma_v = {:.3g} m/s, sigma_w = {:.3g} rad/s from its jitter "
        "(sigma_xy = {:.3g} mm, sigma_theta = {:.3g} mrad over {} samples){}",
        rate, std::sqrt(v_var), std::sqrt(w_var), 1e3 * j.sigma_xy_m, 1e3 * j.sigma_theta_rad, j.triples,
        from_ticks ? " and the encoders' quantisation" : "");
  } else {
    in.ext_noise = fmt::format(
        "derived from the ground truth at {:g} Hz; sigma_v = {:.3g} m/s, sigma_w = {:.3g} "
        "rad/s as given",
        rate, std::sqrt(v_var), std::sqrt(w_var));
  }
  return {v_var, w_var};
}

// Samples of velocities derived from the ground truth by central
// differences at ext_from_gt_rate_hz.
void add_derived_samples(const objectives::PoseSeries& gt, const CalibrationInputOptions& options,
                         bool from_ticks, double ticks_per_rev, std::size_t first_rated, CalibrationInput& in,
                         SampleAdder& adder) {
  const double rate = options.ext_from_gt_rate_hz;
  const double period = 1.0 / rate;
  const double half = 0.5 * period;
  const auto [v_var, w_var] = derived_variances(gt, options, from_ticks, ticks_per_rev, in);
  in.ext_sigma_v_m_s = std::sqrt(v_var);
  in.ext_sigma_w_rad_s = std::sqrt(w_var);
  const double k_first = std::ceil((gt.t.front() + half) * rate);
  const double k_last = std::floor((gt.t.back() - half) * rate);
  for (double k = k_first; k <= k_last; k += 1.0) {
    const double tk = k / rate;
    const std::size_t row = adder.row_at(tk + kSameInstantS);
    if (row == adder.n_rows() || row < first_rated) continue;
    const auto vel = objectives::central_difference_velocity(gt, tk, half, 2.0 * period);
    if (!vel) continue;
    filters::CalibSample s;
    s.v_m_s = vel->v_m_s;
    s.w_rad_s = vel->w_rad_s;
    s.v_var = v_var;
    s.w_var = w_var;
    adder.add(tk, row, s);
  }
}

// Samples of the track's own external velocities (v_ext, w_ext).
void add_track_samples(const tracks::Track& track, const CalibrationInputOptions& options,
                       const std::vector<std::size_t>& track_row, std::size_t first_rated, CalibrationInput& in,
                       SampleAdder& adder) {
  const std::size_t n_rows = adder.n_rows();
  const auto& v_ext = track.col(tracks::Col::v_ext);
  const auto& w_ext = track.col(tracks::Col::w_ext);
  const auto& v_var = track.col(tracks::Col::v_ext_var);
  const auto& w_var = track.col(tracks::Col::w_ext_var);
  std::size_t row = n_rows;  // odometry row at or before track row i
  std::size_t next = 0;      // next odometry row to pass
  for (std::size_t i = 0; i < track.size(); ++i) {
    while (next < n_rows && track_row[next] <= i) row = next++;
    if (std::isnan(v_ext[i]) || std::isnan(w_ext[i])) continue;
    if (row == n_rows || row < first_rated) continue;
    filters::CalibSample s;
    s.v_m_s = v_ext[i];
    s.w_rad_s = w_ext[i];
    s.v_var = objectives::positive_or(v_var, i, options.default_v_var);
    s.w_var = objectives::positive_or(w_var, i, options.default_w_var);
    adder.add(track.t()[i], row, s);
  }
  in.ext_noise = "the track's v_ext/w_ext (variances from v_ext_var/w_ext_var where given, else the defaults)";
}

// The position fixes (aps_x, aps_y) within the odometry's time span.
void add_fixes(const tracks::Track& track, CalibrationInput& in) {
  const auto& t = track.t();
  for (std::size_t i = 0; track.has_aps() && i < track.size(); ++i) {
    if (!track.at(tracks::Col::aps_x, i) || !track.at(tracks::Col::aps_y, i)) continue;
    if (t[i] < in.t.front() || t[i] > in.t.back()) continue;
    in.fix_t.push_back(t[i]);
    in.fix_x.push_back(track.col(tracks::Col::aps_x)[i]);
    in.fix_y.push_back(track.col(tracks::Col::aps_y)[i]);
    const bool var = track.at(tracks::Col::aps_var_x, i) && track.at(tracks::Col::aps_var_y, i);
    in.fix_var_x.push_back(var ? track.col(tracks::Col::aps_var_x)[i] : std::nan(""));
    in.fix_var_y.push_back(var ? track.col(tracks::Col::aps_var_y)[i] : std::nan(""));
  }
}

}  // namespace

const filters::OdometryParams& TruthSchedule::at(double t_s) const {
  if (params.empty() || from_s.size() != params.size())
    throw std::logic_error("TruthSchedule::at on an empty or inconsistent schedule");
  std::size_t k = 0;
  while (k + 1 < from_s.size() && from_s[k + 1] <= t_s) ++k;
  return params[k];
}

std::vector<double> TruthSchedule::change_times() const {
  if (from_s.size() <= 1) return {};
  return std::vector<double>(from_s.begin() + 1, from_s.end());
}

bool CalibrationInputOptions::IsValid(std::string* why) const {
  if (!(wheel_rate_window_s >= 0.0 && wheel_rate_window_s <= 10.0))
    return core::invalid(why,
                         fmt::format("wheel_rate_window_s = {} must be in [0, 10] s", wheel_rate_window_s));
  if (!(ext_from_gt_rate_hz >= 0.0 && ext_from_gt_rate_hz <= kMaxExtFromGtRateHz))
    return core::invalid(why, fmt::format("ext_from_gt_rate_hz = {} must be in [0, {}] Hz (0: use v_ext/w_ext)",
                                          ext_from_gt_rate_hz, kMaxExtFromGtRateHz));
  if (!std::isfinite(default_v_var) || default_v_var <= 0.0)
    return core::invalid(why, fmt::format("default_v_var = {} must be a finite number > 0 [(m/s)^2]",
                                          default_v_var));
  if (!std::isfinite(default_w_var) || default_w_var <= 0.0)
    return core::invalid(why, fmt::format("default_w_var = {} must be a finite number > 0 [(rad/s)^2]",
                                          default_w_var));
  return true;
}

std::optional<TruthSchedule> truth_from_metadata(const tracks::TrackMeta& meta) {
  const std::optional<std::string> text = meta.get("sim.effects");
  if (!text || !meta.wheel_radius_left_m || !meta.wheel_radius_right_m || !meta.wheel_base_m)
    return std::nullopt;

  sim::Effects fx;
  const std::string_view whole = trim(*text);
  if (whole != "none") {
    std::string_view rest = whole;
    while (true) {
      const auto semi = rest.find(';');
      const std::string_view part = trim(rest.substr(0, semi));
      if (part.empty())
        fail(meta.name, fmt::format("sim.effects '{}': empty effect; expected 'none' or "
                                    "NAME:PARAM=VALUE,... parts separated by '; '",
                                    whole));
      try {
        sim::apply_effect(fx, sim::parse_effect_spec(part));
      } catch (const std::invalid_argument& e) {
        fail(meta.name, fmt::format("sim.effects: {}", e.what()));
      }
      if (semi == std::string_view::npos) break;
      rest = rest.substr(semi + 1);
    }
  }

  filters::OdometryParams base;
  base.wheel_radius_left_m = *meta.wheel_radius_left_m;
  base.wheel_radius_right_m = *meta.wheel_radius_right_m;
  base.wheel_base_m = *meta.wheel_base_m;
  if (fx.radius_error) {
    base.wheel_radius_left_m *= fx.radius_error->scale_l;
    base.wheel_radius_right_m *= fx.radius_error->scale_r;
  }
  if (fx.wheel_base_error) base.wheel_base_m *= fx.wheel_base_error->scale;

  TruthSchedule out;
  out.from_s.push_back(-std::numeric_limits<double>::infinity());
  out.params.push_back(base);
  if (fx.radius_step) {
    filters::OdometryParams after = base;
    after.wheel_radius_left_m *= fx.radius_step->scale_l;
    after.wheel_radius_right_m *= fx.radius_step->scale_r;
    out.from_s.push_back(fx.radius_step->t);
    out.params.push_back(after);
  }
  return out;
}

CalibrationInput build_calibration_input(const tracks::Track& track, const CalibrationInputOptions& options) {
  const std::string& name = track.name();
  std::string why;
  if (!options.IsValid(&why)) fail(name, "invalid calibration input options: " + why);

  CalibrationInput in;
  in.track_name = name;
  const bool from_ticks = track.has_ticks();
  if (!from_ticks && !track.has_wheel_rates())
    fail(name, "no wheel odometry (ticks_l/ticks_r or omega_l/omega_r): calibration needs wheel rates");
  const double ticks_per_rev = read_nominal(track, from_ticks, in);
  in.truth = truth_from_metadata(track.meta());

  // --- ground truth ------------------------------------------------------------
  const objectives::PoseSeries gt = objectives::ground_truth_series(track);
  in.has_gt = gt.size() >= 2;

  const bool derive = options.ext_from_gt_rate_hz > 0.0;
  const bool has_ext = track.has(tracks::Col::v_ext) && track.has(tracks::Col::w_ext);
  if (derive && !in.has_gt)
    fail(name, fmt::format("no ground truth (gt_x, gt_y, gt_theta in at least two rows) to derive "
                           "external velocities from at {} Hz",
                           options.ext_from_gt_rate_hz));
  if (!derive && !has_ext && options.require_velocity_samples)
    fail(name, in.has_gt ? "no external velocities (v_ext, w_ext); derive them from the ground truth "
                           "instead (ext_from_gt_rate_hz > 0)"
                         : "no external velocities (v_ext, w_ext) and no ground truth (gt_x, gt_y, "
                           "gt_theta) to derive them from");

  // --- odometry rows ---------------------------------------------------------
  const std::vector<std::size_t> track_row = read_odometry_rows(track, from_ticks, ticks_per_rev, in);
  if (in.t.size() < 2) fail(name, "fewer than two odometry rows: no wheel rate to calibrate with");
  // The first odometry row with a rate: row 1 for ticks, row 0 for omega.
  const std::size_t first_rated = from_ticks ? 1 : 0;
  ground_truth_at_rows(gt, in);

  // --- samples -----------------------------------------------------------------
  SampleAdder adder(in, options, from_ticks);
  if (derive)
    add_derived_samples(gt, options, from_ticks, ticks_per_rev, first_rated, in, adder);
  else if (has_ext)
    add_track_samples(track, options, track_row, first_rated, in, adder);
  add_fixes(track, in);
  if (in.samples.empty() && (derive || has_ext || options.require_velocity_samples))
    fail(name, derive ? "no calibration sample: no ground-truth velocity window overlaps the wheel odometry"
                      : "no calibration sample: no row with both v_ext and w_ext after the first "
                        "odometry rate");
  return in;
}

}  // namespace odotune::calibration
