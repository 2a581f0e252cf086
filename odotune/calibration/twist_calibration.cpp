#include <odotune/calibration/twist_calibration.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>

#include <ceres/ceres.h>
#include <fmt/format.h>

#include <odotune/calibration/ceres_fit.h>
#include <odotune/calibration/fix_groups.h>
#include <odotune/core/ceres_options.h>
#include <odotune/core/why.h>
#include <odotune/tracks/body_velocity.h>

namespace odotune::calibration {

namespace {

enum ScaleParam : int { kScaleV = 0, kScaleW = 1, kScaleParams = 2 };
enum TwistStartParam : int {
  kTwistStartX = 0,
  kTwistStartY = 1,
  kTwistStartHeading = 2,
  kTwistStartParams = 3
};

constexpr double kTwistLowerBoundFraction = 1e-2;  // scales ≥ 1 % (positivity only)
constexpr std::size_t kTwistMinFixesPerSegment = 3;
constexpr int kTwistHeadingGrid = 16;
constexpr double kMaxGtGapS = 0.5;  // a longer gap in the ground truth ends a segment [s]

// A reference position reached after `step` steps of its segment (0: at the start).
struct Ref {
  std::size_t step;
  double x_m, y_m;
  double theta_rad = 0.0;  // ground truth's heading (fixes: unused)
};

struct TwistSegment {
  const tracks::BodyVelocityIntegral* body = nullptr;
  double t0 = 0.0;
  std::vector<double> t;       // step ends [s]
  std::vector<double> dv, dw;  // ∫v [m], ∫w [rad] over each step at the current delay, unscaled
  std::vector<Ref> refs;
  std::array<double, kTwistStartParams> start{};
  bool fixes = false;  // start pose fitted (fixes) or the ground truth's

  void set_delay(double delay_s) {
    dv.resize(t.size());
    dw.resize(t.size());
    double prev = t0;
    for (std::size_t k = 0; k < t.size(); ++k) {
      const auto m = body->mean(prev, t[k], delay_s);
      dv[k] = m[0] * (t[k] - prev);
      dw[k] = m[1] * (t[k] - prev);
      prev = t[k];
    }
  }
};

// Dead reckoning of one segment: parameter blocks the scales and the start
// pose; residuals (x − x_ref, y − y_ref) per reference [m].
struct TwistSegmentDeadReckoning {
  const TwistSegment* seg;
  template <typename T>
  bool operator()(T const* const* p, T* res) const {
    const T* s = p[0];
    const T* st = p[1];
    T x = st[kTwistStartX], y = st[kTwistStartY], h = st[kTwistStartHeading];
    std::size_t r = 0;
    for (std::size_t k = 0;; ++k) {
      for (; r < seg->refs.size() && seg->refs[r].step == k; ++r) {
        res[2 * r] = x - seg->refs[r].x_m;
        res[2 * r + 1] = y - seg->refs[r].y_m;
      }
      if (k == seg->t.size() || r == seg->refs.size()) break;
      const T ds = s[kScaleV] * seg->dv[k], dth = s[kScaleW] * seg->dw[k];
      using std::cos;
      using std::sin;
      const T mid = h + 0.5 * dth;
      x += ds * cos(mid);
      y += ds * sin(mid);
      h += dth;
    }
    return true;
  }
  double sum_squares(const double* scales, const double* start) const {
    std::vector<double> r(2 * seg->refs.size());
    const double* p[] = {scales, start};
    (*this)(p, r.data());
    double sum = 0.0;
    for (double v : r) sum += v * v;
    return sum;
  }
};

[[noreturn]] void fail_twist(const std::string& what) {
  throw std::invalid_argument("twist calibration: " + what);
}

// Step ends from t0 to the last reference: every reference time, and
// enough points between for steps of at most step_s.
void add_steps(TwistSegment& seg, const std::vector<double>& ref_t, double step_s) {
  double prev = seg.t0;
  for (std::size_t i = 0; i < ref_t.size(); ++i) {
    if (ref_t[i] <= prev) {
      seg.refs[i].step = seg.t.size();
      continue;
    }
    const auto n = static_cast<std::size_t>(std::ceil((ref_t[i] - prev) / step_s - 1e-9));
    for (std::size_t j = 1; j < n; ++j)
      seg.t.push_back(prev + (ref_t[i] - prev) * static_cast<double>(j) / static_cast<double>(n));
    seg.t.push_back(ref_t[i]);
    seg.refs[i].step = seg.t.size();
    prev = ref_t[i];
  }
}

struct GtRow {
  double t, x, y, theta;
};

// Ground-truth segments inside the body velocities' span (header comment).
void twist_ground_truth_segments(const tracks::Track& track, const tracks::BodyVelocityIntegral& body,
                                 double segment_s, const TwistCalibrationOptions& o,
                                 std::vector<TwistSegment>* out) {
  std::vector<GtRow> gt;
  const double t_lo = body.t().front(), t_hi = body.t().back();
  for (std::size_t i = 0; i < track.size(); ++i) {
    const double t = track.t()[i];
    if (t < t_lo || t > t_hi || !track.at(tracks::Col::gt_x, i) || !track.at(tracks::Col::gt_y, i) ||
        !track.at(tracks::Col::gt_theta, i))
      continue;
    gt.push_back({t, track.col(tracks::Col::gt_x)[i], track.col(tracks::Col::gt_y)[i],
                  track.col(tracks::Col::gt_theta)[i]});
  }
  std::size_t a = 0;
  while (a + 1 < gt.size()) {
    TwistSegment seg;
    seg.body = &body;
    seg.t0 = gt[a].t;
    seg.start = {gt[a].x, gt[a].y, gt[a].theta};
    std::vector<double> ref_t;
    std::size_t q = a + 1;
    double last = gt[a].t;
    for (; q < gt.size() && gt[q].t - gt[q - 1].t <= kMaxGtGapS; ++q) {
      if (gt[q].t - last >= o.reference_step_s - 1e-9) {
        ref_t.push_back(gt[q].t);
        seg.refs.push_back({0, gt[q].x, gt[q].y, gt[q].theta});
        last = gt[q].t;
      }
      if (segment_s > 0.0 && gt[q].t - gt[a].t >= segment_s) break;
    }
    if (!seg.refs.empty()) {
      add_steps(seg, ref_t, o.step_s);
      out->push_back(std::move(seg));
    }
    a = (q < gt.size() && gt[q].t - gt[q - 1].t <= kMaxGtGapS) ? q : q + 1;
    if (q >= gt.size()) break;
  }
}

// Fix segments: groups of fixes spanning segment_s (0: all), each of at
// least kTwistMinFixesPerSegment fixes (a short tail joins the group before).
void twist_fix_segments(const tracks::Track& track, const tracks::BodyVelocityIntegral& body, double segment_s,
                        const TwistCalibrationOptions& o, std::vector<TwistSegment>* out) {
  std::vector<GtRow> fixes;
  for (std::size_t i = 0; i < track.size(); ++i) {
    const double t = track.t()[i];
    if (t < body.t().front() || t > body.t().back() || !track.at(tracks::Col::aps_x, i) ||
        !track.at(tracks::Col::aps_y, i))
      continue;
    fixes.push_back({t, track.col(tracks::Col::aps_x)[i], track.col(tracks::Col::aps_y)[i], 0.0});
  }
  std::vector<double> fix_t;
  fix_t.reserve(fixes.size());
  for (const GtRow& f : fixes) fix_t.push_back(f.t);
  for (const auto& [first, last] : fix_groups(fix_t, segment_s, kTwistMinFixesPerSegment)) {
    if (last - first + 1 < kTwistMinFixesPerSegment) continue;
    TwistSegment seg;
    seg.body = &body;
    seg.fixes = true;
    seg.t0 = fixes[first].t;
    seg.start = {fixes[first].x, fixes[first].y, 0.0};
    std::vector<double> ref_t;
    for (std::size_t k = first; k <= last; ++k) {
      ref_t.push_back(fixes[k].t);
      seg.refs.push_back({0, fixes[k].x, fixes[k].y, 0.0});
    }
    add_steps(seg, ref_t, o.step_s);
    out->push_back(std::move(seg));
  }
}

struct Runs {
  std::vector<tracks::BodyVelocityIntegral> bodies;  // one per track, stable (reserved)
  long ground_truth_runs = 0, fix_runs = 0;
};

std::vector<TwistSegment> twist_build_segments(const std::vector<const tracks::Track*>& tracks, Runs& runs,
                                               double segment_s, const TwistCalibrationOptions& o) {
  std::vector<TwistSegment> segs;
  runs.ground_truth_runs = runs.fix_runs = 0;
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const tracks::Track& track = *tracks[i];
    const tracks::BodyVelocityIntegral& body = runs.bodies[i];
    const std::size_t before = segs.size();
    if (track.has_gt()) {
      twist_ground_truth_segments(track, body, segment_s, o, &segs);
      ++runs.ground_truth_runs;
    } else {
      twist_fix_segments(track, body, segment_s, o, &segs);
      ++runs.fix_runs;
    }
    if (segs.size() == before)
      fail_twist(fmt::format(
          "track '{}' has no reference to fit dead reckoning to: expected ground truth (gt_x, gt_y, "
          "gt_theta) or at least {} position fixes (aps_x, aps_y) within its v_cmd/w_cmd rows",
          track.name(), kTwistMinFixesPerSegment));
  }
  return segs;
}

void set_delay(std::vector<TwistSegment>& segs, double delay_s, const double* scales) {
  for (TwistSegment& seg : segs) {
    seg.set_delay(delay_s);
    if (!seg.fixes) continue;
    // The best of kTwistHeadingGrid start headings under the current scales.
    double best = 0.0, best_cost = std::numeric_limits<double>::infinity();
    std::array<double, kTwistStartParams> st = seg.start;
    for (int i = 0; i < kTwistHeadingGrid; ++i) {
      st[kTwistStartHeading] = 2.0 * std::numbers::pi * i / kTwistHeadingGrid - std::numbers::pi;
      const double c = TwistSegmentDeadReckoning{&seg}.sum_squares(scales, st.data());
      if (c < best_cost) best_cost = c, best = st[kTwistStartHeading];
    }
    seg.start[kTwistStartHeading] = best;
  }
}

struct Fit {
  double cost = 0.0;  // Ceres' final (robust) cost
  ceres::Solver::Summary summary;
  std::array<double, kScaleParams> sd{};
};

// Fits the scales (in place) and the fix segments' start poses.
Fit twist_solve(std::vector<TwistSegment>& segs, double* scales, const TwistCalibrationOptions& o,
                bool covariance) {
  ceres::Problem problem;
  ceres::LossFunction* loss = new ceres::HuberLoss(o.loss_scale_m);  // shared; the problem deletes it
  long points = 0, free_start = 0;
  for (TwistSegment& seg : segs) {
    auto* cost = new ceres::DynamicAutoDiffCostFunction<TwistSegmentDeadReckoning, 5>(
        new TwistSegmentDeadReckoning{&seg});
    cost->AddParameterBlock(kScaleParams);
    cost->AddParameterBlock(kTwistStartParams);
    cost->SetNumResiduals(static_cast<int>(2 * seg.refs.size()));
    problem.AddResidualBlock(cost, loss, scales, seg.start.data());
    points += static_cast<long>(seg.refs.size());
    if (seg.fixes)
      free_start += kTwistStartParams;
    else
      problem.SetParameterBlockConstant(seg.start.data());
  }
  for (int i = 0; i < kScaleParams; ++i) problem.SetParameterLowerBound(scales, i, kTwistLowerBoundFraction);
  Fit fit;
  ceres::Solve(core::deterministic_solver_options(o.max_iterations, core::FitTolerance::calibration), &problem,
               &fit.summary);
  fit.cost = fit.summary.final_cost;
  fit.sd.fill(std::nan(""));
  if (covariance) {
    const double dof = 2.0 * static_cast<double>(points) - static_cast<double>(kScaleParams + free_start);
    const std::vector<double> sd = scaled_standard_errors(problem, scales, kScaleParams, fit.cost, dof);
    fit.sd = {sd[0], sd[1]};
  }
  return fit;
}

double twist_rmse(const std::vector<TwistSegment>& segs, const double* scales, long points) {
  double s = 0.0;
  for (const TwistSegment& seg : segs)
    s += TwistSegmentDeadReckoning{&seg}.sum_squares(scales, seg.start.data());
  return points > 0 ? std::sqrt(s / static_cast<double>(points)) : 0.0;
}

// The delay of least cost on the warm-start segments (header comment); the
// scales stay at the best point's fit.
double search_delay(std::vector<TwistSegment>& warm, double* scales, const TwistCalibrationOptions& o) {
  double best = 0.0, best_cost = std::numeric_limits<double>::infinity();
  std::array<double, kScaleParams> best_scales{scales[0], scales[1]};
  auto try_delay = [&](double d) {
    std::array<double, kScaleParams> s{1.0, 1.0};
    set_delay(warm, d, s.data());
    const Fit f = twist_solve(warm, s.data(), o, false);
    if (f.cost < best_cost) best_cost = f.cost, best = d, best_scales = s;
  };
  const auto coarse = static_cast<int>(std::floor(o.max_delay_s / o.delay_step_s + 1e-9));
  for (int i = 0; i <= coarse; ++i) try_delay(i * o.delay_step_s);
  const double centre = best;
  const auto fine = static_cast<int>(std::floor(o.delay_step_s / o.fine_delay_step_s + 1e-9));
  for (int i = -fine; i <= fine; ++i) {
    const double d = centre + i * o.fine_delay_step_s;
    if (i != 0 && d >= 0.0 && d <= o.max_delay_s) try_delay(d);
  }
  scales[0] = best_scales[0];
  scales[1] = best_scales[1];
  return best;
}

}  // namespace

TwistScore score_twist(const tracks::Track& track, const filters::TwistCorrection& c) {
  const tracks::BodyVelocityIntegral body(track);
  TwistScore out;
  out.pose_rmse_m = out.heading_rmse_rad = std::nan("");
  if (body.size() < 2) return out;
  std::vector<TwistSegment> segs;
  TwistCalibrationOptions o;
  o.reference_step_s = 1e-9;  // every ground-truth row
  twist_ground_truth_segments(track, body, 0.0, o, &segs);
  if (segs.empty()) return out;
  // One dead reckoning from the first pose, on across gaps in the ground truth.
  double x = segs[0].start[kTwistStartX], y = segs[0].start[kTwistStartY],
         h = segs[0].start[kTwistStartHeading];
  double t_prev = segs[0].t0, sum_xy = 0.0, sum_th = 0.0;
  for (const TwistSegment& seg : segs)
    for (const Ref& r : seg.refs) {
      const double t_ref = seg.t[r.step - 1];  // a ground-truth reference follows at least one step
      const auto n = static_cast<int>(std::ceil((t_ref - t_prev) / o.step_s - 1e-9));
      for (int j = 1; j <= n; ++j) {
        const double t0 = t_prev + (t_ref - t_prev) * (j - 1) / n, t1 = t_prev + (t_ref - t_prev) * j / n;
        const auto m = body.mean(t0, t1, c.delay_s);
        const double ds = c.scale_v * m[0] * (t1 - t0), dth = c.scale_w * m[1] * (t1 - t0);
        x += ds * std::cos(h + 0.5 * dth);
        y += ds * std::sin(h + 0.5 * dth);
        h += dth;
      }
      t_prev = std::max(t_prev, t_ref);
      sum_xy += (x - r.x_m) * (x - r.x_m) + (y - r.y_m) * (y - r.y_m);
      const double eth = std::remainder(h - r.theta_rad, 2.0 * std::numbers::pi);
      sum_th += eth * eth;
      ++out.samples;
    }
  if (out.samples == 0) return out;
  out.pose_rmse_m = std::sqrt(sum_xy / static_cast<double>(out.samples));
  out.heading_rmse_rad = std::sqrt(sum_th / static_cast<double>(out.samples));
  return out;
}

bool TwistCalibrationOptions::IsValid(std::string* why) const {
  const auto positive = [](double x) { return std::isfinite(x) && x > 0.0; };
  if (!(std::isfinite(segment_s) && segment_s >= 0.0))
    return core::invalid(why, fmt::format("segment_s = {} must be a finite number >= 0 [s] (0: whole runs)",
                                          segment_s));
  if (!positive(warm_start_segment_s))
    return core::invalid(why, fmt::format("warm_start_segment_s = {} must be > 0 [s]", warm_start_segment_s));
  if (!positive(step_s) || !positive(reference_step_s))
    return core::invalid(why, fmt::format("step_s = {}, reference_step_s = {}: expected > 0 [s]", step_s,
                                          reference_step_s));
  if (!(std::isfinite(max_delay_s) && max_delay_s >= 0.0))
    return core::invalid(why, fmt::format("max_delay_s = {} must be a finite number >= 0 [s]", max_delay_s));
  if (!positive(delay_step_s) || !positive(fine_delay_step_s) || fine_delay_step_s > delay_step_s)
    return core::invalid(
        why, fmt::format("delay_step_s = {}, fine_delay_step_s = {}: expected 0 < fine <= coarse [s]",
                         delay_step_s, fine_delay_step_s));
  if (!positive(loss_scale_m))
    return core::invalid(why, fmt::format("loss_scale_m = {} must be > 0 [m]", loss_scale_m));
  if (max_iterations < 1)
    return core::invalid(why, fmt::format("max_iterations = {} must be >= 1", max_iterations));
  return true;
}

TwistCalibrationSummary calibrate_twist(const std::vector<const tracks::Track*>& tracks,
                                        tracks::OdometryInput input, const TwistCalibrationOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) fail_twist(why);
  if (input == tracks::OdometryInput::wheels)
    fail_twist("wheel odometry is calibrated by its geometry (pose_calibration.h)");
  if (tracks.empty()) fail_twist("no track given");
  Runs runs;
  runs.bodies.reserve(tracks.size());
  for (const tracks::Track* t : tracks) {
    if (t == nullptr) fail_twist("null track");
    runs.bodies.emplace_back(*t);
    if (runs.bodies.back().size() < 2)
      fail_twist(fmt::format("track '{}': fewer than two v_cmd/w_cmd rows", t->name()));
  }
  TwistCalibrationSummary out;
  out.input = input;
  std::array<double, kScaleParams> scales{1.0, 1.0};
  const bool delay = options.fit_delay && input == tracks::OdometryInput::commands;
  if (delay) {
    std::vector<TwistSegment> warm = twist_build_segments(tracks, runs, options.warm_start_segment_s, options);
    out.params.delay_s = search_delay(warm, scales.data(), options);
  }
  std::vector<TwistSegment> segs = twist_build_segments(tracks, runs, options.segment_s, options);
  for (const TwistSegment& s : segs) out.reference_points += static_cast<long>(s.refs.size());
  out.segments = static_cast<long>(segs.size());
  out.ground_truth_runs = runs.ground_truth_runs;
  out.fix_runs = runs.fix_runs;
  const std::array<double, kScaleParams> identity{1.0, 1.0};
  set_delay(segs, 0.0, identity.data());
  out.initial_rmse_m = twist_rmse(segs, identity.data(), out.reference_points);
  if (!delay && options.segment_s != options.warm_start_segment_s) {  // warm start, as the wheel fit
    std::vector<TwistSegment> warm = twist_build_segments(tracks, runs, options.warm_start_segment_s, options);
    set_delay(warm, 0.0, scales.data());
    twist_solve(warm, scales.data(), options, false);
  }
  set_delay(segs, out.params.delay_s, scales.data());
  const Fit fit = twist_solve(segs, scales.data(), options, true);
  out.params.scale_v = scales[kScaleV];
  out.params.scale_w = scales[kScaleW];
  out.sd_scale_v = fit.sd[kScaleV];
  out.sd_scale_w = fit.sd[kScaleW];
  out.final_rmse_m = twist_rmse(segs, scales.data(), out.reference_points);
  out.converged = fit.summary.termination_type == ceres::CONVERGENCE;
  out.termination = fit.summary.message;
  std::string refs;
  if (out.ground_truth_runs > 0) refs = fmt::format("ground truth ({} run(s))", out.ground_truth_runs);
  if (out.fix_runs > 0)
    refs += fmt::format("{}position fixes ({} run(s), start pose fitted per segment)",
                        refs.empty() ? "" : " and ", out.fix_runs);
  out.residuals = fmt::format("pose residuals: {} reference positions from {} over {} {}{}; Huber {:g} m",
                              out.reference_points, refs, out.segments,
                              options.segment_s > 0.0 ? fmt::format("segments of {:g} s", options.segment_s)
                                                      : std::string("whole-run segments"),
                              delay ? fmt::format(" (delay searched 0-{:g} s on {:g} s segments)",
                                                  options.max_delay_s, options.warm_start_segment_s)
                                    : fmt::format(" (warm start on {:g} s segments)",
                                                  options.warm_start_segment_s),
                              options.loss_scale_m);
  return out;
}

}  // namespace odotune::calibration
