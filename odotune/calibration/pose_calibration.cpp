#include <odotune/calibration/pose_calibration.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numbers>
#include <stdexcept>

#include <ceres/ceres.h>
#include <fmt/format.h>

#include <odotune/calibration/ceres_fit.h>
#include <odotune/calibration/fix_groups.h>
#include <odotune/core/ceres_options.h>
#include <odotune/core/planar_motion.h>
#include <odotune/core/why.h>

namespace odotune::calibration {

namespace {

// Parameter block layout: θ = (R_R, R_L, D) [m] (as batch_calibration.cpp),
// and a segment's start pose (x, y, heading) [m, m, rad].
enum PoseParam : int { kRadiusRight = 0, kRadiusLeft = 1, kWheelBase = 2, kPoseParams = 3 };
enum StartParam : int { kStartX = 0, kStartY = 1, kStartHeading = 2, kStartParams = 3 };

// Lower bound of every parameter as a fraction of its initial value (as the
// velocity-domain fit).
constexpr double kLowerBoundFraction = 1e-2;
// Fewest fixes a fix segment needs: its start pose has three unknowns.
constexpr std::size_t kMinFixesPerSegment = 3;
// Headings tried to start a fix segment's heading (the fit refines it).
constexpr int kHeadingGrid = 16;

// One reference position of a segment: reached by integrating rows a+1 ..
// row−1 whole and `fraction` ∈ [0, 1] of row `row`'s wheel travel.
struct RefPoint {
  std::size_t row;
  double fraction;
  double x_m, y_m;
};

// Dead reckoning of one segment (header comment). Parameter blocks: θ, the
// start pose; residuals: (x − x_ref, y − y_ref) per reference point [m].
struct SegmentDeadReckoning {
  const CalibrationInput* in;
  std::size_t a;  // start row
  std::vector<RefPoint> refs;

  template <typename T>
  bool operator()(T const* const* p, T* res) const {
    const T* th = p[0];
    const T* s = p[1];
    T x = s[kStartX], y = s[kStartY], h = s[kStartHeading];
    std::size_t k = 0;
    for (std::size_t r = a + 1; k < refs.size(); ++r) {
      const double dt = in->t[r] - in->t[r - 1];
      const T l = in->omega_l[r] * dt * th[kRadiusLeft];
      const T rr = in->omega_r[r] * dt * th[kRadiusRight];
      for (; k < refs.size() && refs[k].row == r; ++k) {
        T px = x, py = y, ph = h;
        const double f = refs[k].fraction;
        if (f > 0.0) core::midpoint_advance(&px, &py, &ph, T(f) * l, T(f) * rr, th[kWheelBase]);
        res[2 * k] = px - refs[k].x_m;
        res[2 * k + 1] = py - refs[k].y_m;
      }
      core::midpoint_advance(&x, &y, &h, l, rr, th[kWheelBase]);
    }
    return true;
  }

  double sum_squares(const double* theta, const double* start) const {
    std::vector<double> r(2 * refs.size());
    const double* p[] = {theta, start};
    (*this)(p, r.data());
    double s = 0.0;
    for (double v : r) s += v * v;
    return s;
  }
};

struct Segment {
  SegmentDeadReckoning f;
  double start[kStartParams];
  bool fixes = false;  // start pose fitted whole (fixes) or from the reference
};

// Ground-truth segments: stretches of consecutive rows with ground truth,
// cut every segment_s (0: never).
void ground_truth_segments(const CalibrationInput& in, double segment_s, std::vector<Segment>* out) {
  const std::size_t n = in.t.size();
  std::size_t r = 0;
  while (r < n) {
    while (r < n && !in.has_gt_row(r)) ++r;
    if (r >= n) break;
    Segment seg;
    seg.f.in = &in;
    seg.f.a = r;
    seg.start[kStartX] = in.gt_x[r];
    seg.start[kStartY] = in.gt_y[r];
    seg.start[kStartHeading] = in.gt_theta[r];
    std::size_t q = r + 1;
    for (; q < n && in.has_gt_row(q); ++q) {
      seg.f.refs.push_back({q, 1.0, in.gt_x[q], in.gt_y[q]});
      if (segment_s > 0.0 && in.t[q] - in.t[r] >= segment_s) break;
    }
    if (!seg.f.refs.empty()) out->push_back(std::move(seg));
    // The next segment starts where this one ended (abutting), or after the gap.
    r = (q < n && in.has_gt_row(q)) ? q : q + 1;
  }
}

// Fix segments: groups of fixes spanning segment_s (0: all), each of at
// least kMinFixesPerSegment fixes (a short tail joins the group before).
void fix_segments(const CalibrationInput& in, double segment_s, std::vector<Segment>* out) {
  for (const auto& [first, last] : fix_groups(in.fix_t, segment_s, kMinFixesPerSegment)) {
    if (last - first + 1 < kMinFixesPerSegment) continue;
    Segment seg;
    seg.fixes = true;
    seg.f.in = &in;
    // The start row: the odometry row at or before the first fix.
    const auto it = std::upper_bound(in.t.begin(), in.t.end(), in.fix_t[first]);
    seg.f.a = static_cast<std::size_t>(std::max<std::ptrdiff_t>(it - in.t.begin() - 1, 0));
    if (seg.f.a + 1 >= in.t.size()) continue;
    for (std::size_t k = first; k <= last; ++k) {
      // The row whose interval (t[row−1], t[row]] holds the fix (row > a).
      const auto up = std::lower_bound(in.t.begin(), in.t.end(), in.fix_t[k]);
      std::size_t row = std::max(static_cast<std::size_t>(up - in.t.begin()), seg.f.a + 1);
      row = std::min(row, in.t.size() - 1);
      const double span = in.t[row] - in.t[row - 1];
      const double f = std::clamp((in.fix_t[k] - in.t[row - 1]) / span, 0.0, 1.0);
      seg.f.refs.push_back({row, f, in.fix_x[k], in.fix_y[k]});
    }
    seg.start[kStartX] = in.fix_x[first];
    seg.start[kStartY] = in.fix_y[first];
    out->push_back(std::move(seg));
  }
}

// The best of kHeadingGrid start headings of a fix segment under θ.
double best_start_heading(const Segment& seg, const double* theta) {
  double best = 0.0, best_cost = std::numeric_limits<double>::infinity();
  double start[kStartParams] = {seg.start[kStartX], seg.start[kStartY], 0.0};
  for (int i = 0; i < kHeadingGrid; ++i) {
    start[kStartHeading] = 2.0 * std::numbers::pi * i / kHeadingGrid - std::numbers::pi;
    const double c = seg.f.sum_squares(theta, start);
    if (c < best_cost) best_cost = c, best = start[kStartHeading];
  }
  return best;
}

double rmse(const std::vector<Segment>& segs, const double* theta, long points) {
  double s = 0.0;
  for (const Segment& seg : segs) s += seg.f.sum_squares(theta, seg.start);
  return points > 0 ? std::sqrt(s / static_cast<double>(points)) : 0.0;
}

}  // namespace

bool PoseCalibrationOptions::IsValid(std::string* why) const {
  if (!(std::isfinite(segment_s) && segment_s >= 0.0))
    return core::invalid(why, fmt::format("segment_s = {} must be a finite number ≥ 0 [s] (0: whole runs)",
                                          segment_s));
  if (!(std::isfinite(loss_scale_m) && loss_scale_m > 0.0))
    return core::invalid(why, fmt::format("loss_scale_m = {} must be a finite number > 0 [m]", loss_scale_m));
  if (!(std::isfinite(warm_start_segment_s) && warm_start_segment_s >= 0.0))
    return core::invalid(
        why, fmt::format("warm_start_segment_s = {} must be a finite number ≥ 0 [s] (0: no warm start)",
                         warm_start_segment_s));
  if (max_iterations < 1)
    return core::invalid(why, fmt::format("max_iterations = {} must be ≥ 1", max_iterations));
  return true;
}

namespace {

// The segments of every input (header), with each fix segment's start
// heading chosen under θ. Throws for a run without reference.
std::vector<Segment> build_segments(const std::vector<const CalibrationInput*>& inputs, double segment_s,
                                    const double* theta, PoseCalibrationSummary* out) {
  std::vector<Segment> segs;
  out->ground_truth_runs = out->fix_runs = 0;
  for (const CalibrationInput* in : inputs) {
    if (!in) throw std::invalid_argument("pose calibration: null input");
    const std::size_t before = segs.size();
    if (in->has_gt) {
      ground_truth_segments(*in, segment_s, &segs);
      ++out->ground_truth_runs;
    } else if (in->fix_t.size() >= kMinFixesPerSegment) {
      fix_segments(*in, segment_s, &segs);
      ++out->fix_runs;
    }
    if (segs.size() == before)
      throw std::invalid_argument(fmt::format(
          "pose calibration: track '{}' has no reference to fit dead reckoning to: expected ground truth "
          "(gt_x, gt_y, gt_theta in at least two odometry rows) or at least {} position fixes (aps_x, aps_y) "
          "within its odometry",
          in->track_name, kMinFixesPerSegment));
  }
  for (Segment& seg : segs)
    if (seg.fixes) seg.start[kStartHeading] = best_start_heading(seg, theta);
  return segs;
}

struct Solved {
  ceres::Solver::Summary summary;
  int start_params_fitted = 0;
  double sd[kPoseParams];
};

// Fits θ (in place) and the segments' free start parameters; with
// `covariance`, the sds of θ (NaN when not computable).
Solved solve(std::vector<Segment>& segs, double* theta, const PoseCalibrationOptions& options,
             const double* lower, bool covariance) {
  Solved out;
  ceres::Problem problem;
  // One loss shared by every block; the problem deletes it once.
  ceres::LossFunction* loss = new ceres::HuberLoss(options.loss_scale_m);
  long points = 0;
  for (Segment& seg : segs) {
    auto* cost =
        new ceres::DynamicAutoDiffCostFunction<SegmentDeadReckoning, int{kPoseParams} + int{kStartParams}>(
            new SegmentDeadReckoning(seg.f));
    cost->AddParameterBlock(kPoseParams);
    cost->AddParameterBlock(kStartParams);
    cost->SetNumResiduals(static_cast<int>(2 * seg.f.refs.size()));
    problem.AddResidualBlock(cost, loss, theta, seg.start);
    points += static_cast<long>(seg.f.refs.size());
    if (seg.fixes) {
      out.start_params_fitted += kStartParams;
    } else if (options.fit_start_heading) {
      problem.SetManifold(seg.start, new ceres::SubsetManifold(kStartParams, {kStartX, kStartY}));
      out.start_params_fitted += 1;
    } else {
      problem.SetParameterBlockConstant(seg.start);
    }
  }
  for (int i = 0; i < kPoseParams; ++i) problem.SetParameterLowerBound(theta, i, lower[i]);

  const ceres::Solver::Options so = core::deterministic_solver_options(options.max_iterations,
                                                                       core::FitTolerance::calibration);
  ceres::Solve(so, &problem, &out.summary);

  const double nan = std::nan("");
  for (double& v : out.sd) v = nan;
  const double dof = 2.0 * static_cast<double>(points) -
                     static_cast<double>(kPoseParams + out.start_params_fitted);
  if (covariance) {
    const std::array<double, 3> sd = scaled_standard_errors(problem, theta, out.summary.final_cost, dof);
    for (int i = 0; i < kPoseParams; ++i) out.sd[i] = sd[static_cast<std::size_t>(i)];
  }
  return out;
}

}  // namespace

PoseCalibrationSummary pose_calibrate(const std::vector<const CalibrationInput*>& inputs,
                                      const filters::OdometryParams& initial,
                                      const PoseCalibrationOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("pose calibration options: " + why);
  if (!initial.IsValid(&why)) throw std::invalid_argument("pose calibration: initial parameters: " + why);
  if (inputs.empty()) throw std::invalid_argument("pose calibration: no input track");

  PoseCalibrationSummary out;
  double theta[kPoseParams];
  theta[kRadiusRight] = initial.wheel_radius_right_m;
  theta[kRadiusLeft] = initial.wheel_radius_left_m;
  theta[kWheelBase] = initial.wheel_base_m;
  double lower[kPoseParams];
  for (int i = 0; i < kPoseParams; ++i) lower[i] = kLowerBoundFraction * theta[i];

  // The requested segments, scored at the initial parameters.
  std::vector<Segment> segs = build_segments(inputs, options.segment_s, theta, &out);
  for (const Segment& seg : segs) out.reference_points += static_cast<long>(seg.f.refs.size());
  out.segments = static_cast<long>(segs.size());
  out.initial_rmse_m = rmse(segs, theta, out.reference_points);

  const double warm = options.warm_start_segment_s;
  const bool warm_start = warm > 0.0 && (options.segment_s <= 0.0 || options.segment_s > warm);
  if (warm_start) {
    PoseCalibrationSummary scratch;
    std::vector<Segment> short_segs = build_segments(inputs, warm, theta, &scratch);
    solve(short_segs, theta, options, lower, false);
    // The requested segments start from the warm start's θ (fix segments
    // choose their start heading again under it).
    segs = build_segments(inputs, options.segment_s, theta, &out);
  }
  const Solved s = solve(segs, theta, options, lower, true);
  out.converged = s.summary.termination_type == ceres::CONVERGENCE;
  out.termination = s.summary.message;
  out.params.wheel_radius_right_m = theta[kRadiusRight];
  out.params.wheel_radius_left_m = theta[kRadiusLeft];
  out.params.wheel_base_m = theta[kWheelBase];
  out.final_rmse_m = rmse(segs, theta, out.reference_points);
  out.sd_radius_right_m = s.sd[kRadiusRight];
  out.sd_radius_left_m = s.sd[kRadiusLeft];
  out.sd_wheel_base_m = s.sd[kWheelBase];

  std::string refs;
  if (out.ground_truth_runs > 0) refs = fmt::format("ground truth ({} run(s))", out.ground_truth_runs);
  if (out.fix_runs > 0)
    refs += fmt::format("{}position fixes ({} run(s), start pose fitted per segment)",
                        refs.empty() ? "" : " and ", out.fix_runs);
  const std::string seg_kind = options.segment_s > 0.0 ? fmt::format("segments of {:g} s", options.segment_s)
                                                       : std::string("whole-run segments");
  out.residuals = fmt::format(
      "pose residuals: {} reference positions from {} over {} {}{}{}; Huber {:g} m", out.reference_points, refs,
      out.segments, seg_kind,
      options.fit_start_heading && out.ground_truth_runs > 0 ? ", start heading fitted" : "",
      warm_start ? fmt::format(" (warm start on {:g} s segments)", warm) : std::string(), options.loss_scale_m);
  return out;
}

}  // namespace odotune::calibration
