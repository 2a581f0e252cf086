#include <odotune/objectives/replay.h>

#include <cmath>
#include <stdexcept>

namespace odotune::objectives {

using filters::Divergence;
using filters::Pose;
using filters::StateCov;

filters::EkfParams ekf_params_for(const ReplayInput& in, const filters::NoiseParams& noise) {
  filters::EkfParams p;
  p.noise = noise;
  p.wheel_base_m = in.wheel_base_m;
  p.initial_pose = in.initial_pose;
  p.initial_cov = in.initial_cov;
  return p;
}

namespace {
// Ekf::update with the row's fix and, when the track gives them, its own variances.
void apply_fix(const ReplayInput& in, std::int32_t fix, filters::Ekf* ekf) {
  const double vx = in.fix_var_x_m2[fix], vy = in.fix_var_y_m2[fix];
  if (std::isnan(vx))
    ekf->update(in.fixes[fix]);
  else
    ekf->update(in.fixes[fix], vx, vy);
}
}  // namespace

ReplayResult replay_ekf(const ReplayInput& in, const filters::NoiseParams& noise, bool keep_trajectory) {
  filters::Ekf ekf(ekf_params_for(in, noise));
  ReplayResult result;
  ErrorAccumulator acc;
  if (keep_trajectory) result.trajectory.reserve(in.gt.size() + 1);
  if (keep_trajectory) result.trajectory.push_back({in.t0_s, ekf.pose()(0), ekf.pose()(1), ekf.pose()(2)});
  for (const ReplayRow& row : in.rows) {
    if (row.step >= 0) ekf.predict(in.steps[row.step], in.abs_yaw_rate_rad_s[row.step]);
    if (row.fix >= 0) {
      apply_fix(in, row.fix, &ekf);
      if (ekf.check() != Divergence::none) break;
    }
    if (row.gt >= 0) {
      const Pose& x = ekf.pose();
      acc.add(std::hypot(x(0) - in.gt[row.gt](0), x(1) - in.gt[row.gt](1)));
      if (keep_trajectory) result.trajectory.push_back({row.t_s, x(0), x(1), x(2)});
    }
  }
  ekf.check();
  result.outcome.divergence = ekf.divergence();
  result.outcome.metrics = acc.metrics();
  return result;
}

std::vector<TrajectoryPoint> ekf_trajectory(const ReplayInput& in, const filters::NoiseParams& noise) {
  filters::Ekf ekf(ekf_params_for(in, noise));
  std::vector<TrajectoryPoint> out;
  out.reserve(in.rows.size() + 1);
  out.push_back({in.t0_s, ekf.pose()(0), ekf.pose()(1), ekf.pose()(2)});
  for (const ReplayRow& row : in.rows) {
    if (row.step >= 0) ekf.predict(in.steps[row.step], in.abs_yaw_rate_rad_s[row.step]);
    if (row.fix >= 0) apply_fix(in, row.fix, &ekf);
    if (ekf.check() != Divergence::none) break;
    out.push_back({row.t_s, ekf.pose()(0), ekf.pose()(1), ekf.pose()(2)});
  }
  return out;
}

FastReplay::FastReplay(const ReplayInput& in)
    : name_(in.track_name),
      steps_(static_cast<long>(in.steps.size())),
      initial_pose_(in.initial_pose),
      initial_cov_(in.initial_cov) {
  ox_.reserve(in.gt.size());
  oy_.reserve(in.gt.size());
  gx_.reserve(in.gt.size());
  gy_.reserve(in.gt.size());

  std::vector<filters::WheelTravel> seg_steps;
  std::vector<double> seg_yaw;
  std::vector<std::int32_t> seg_eval_step;  // per pending sample: steps done in the segment
  std::vector<filters::Position> seg_eval_gt;

  auto close_segment = [&](const filters::Position* fix, double var_x, double var_y) {
    Segment seg;
    std::vector<double> px(seg_steps.size()), py(seg_steps.size());
    seg.moments = filters::reduce_segment(seg_steps, seg_yaw, in.wheel_base_m, px, py);
    seg.eval_begin = static_cast<std::int32_t>(ox_.size());
    for (std::size_t k = 0; k < seg_eval_step.size(); ++k) {
      const std::int32_t done = seg_eval_step[k];
      ox_.push_back(done == 0 ? 0.0 : px[static_cast<std::size_t>(done - 1)]);
      oy_.push_back(done == 0 ? 0.0 : py[static_cast<std::size_t>(done - 1)]);
      gx_.push_back(seg_eval_gt[k](0));
      gy_.push_back(seg_eval_gt[k](1));
    }
    seg.eval_end = static_cast<std::int32_t>(ox_.size());
    seg.has_fix = fix != nullptr;
    if (fix) seg.fix = *fix;
    seg.fix_var_x_m2 = var_x;
    seg.fix_var_y_m2 = var_y;
    segments_.push_back(seg);
    seg_steps.clear();
    seg_yaw.clear();
    seg_eval_step.clear();
    seg_eval_gt.clear();
  };

  for (const ReplayRow& row : in.rows) {
    if (row.step >= 0) {
      seg_steps.push_back(in.steps[row.step]);
      seg_yaw.push_back(in.abs_yaw_rate_rad_s[row.step]);
    }
    // A fix ends the segment; this row's ground truth is compared after the
    // correction, i.e. at the start (o = 0) of the next segment.
    if (row.fix >= 0) close_segment(&in.fixes[row.fix], in.fix_var_x_m2[row.fix], in.fix_var_y_m2[row.fix]);
    if (row.gt >= 0) {
      seg_eval_step.push_back(static_cast<std::int32_t>(seg_steps.size()));
      seg_eval_gt.push_back(in.gt[row.gt]);
    }
  }
  close_segment(nullptr, std::nan(""), std::nan(""));
}

namespace {

// Error samples of one segment: e_k = |p_u + Rot(θ_u)·o_k − g_k|. The hot loop
// of the tuner; compiled for AVX2 as well as the baseline ISA and chosen at
// load time (GCC function multi-versioning), so one binary runs anywhere.
__attribute__((target_clones("avx2", "default"))) void accumulate_errors(
    const double* __restrict ox, const double* __restrict oy, const double* __restrict gx,
    const double* __restrict gy, int n, double px, double py, double c, double s, ErrorAccumulator* acc) {
  double sum = 0.0, sum_sq = 0.0, mx = 0.0;
#pragma omp simd reduction(+ : sum, sum_sq) reduction(max : mx)
  for (int k = 0; k < n; ++k) {
    const double ex = px + c * ox[k] - s * oy[k] - gx[k];
    const double ey = py + s * ox[k] + c * oy[k] - gy[k];
    const double e2 = ex * ex + ey * ey;
    const double e = std::sqrt(e2);
    sum += e;
    sum_sq += e2;
    mx = mx > e ? mx : e;
  }
  acc->sum += sum;
  acc->sum_sq += sum_sq;
  acc->max = acc->max > mx ? acc->max : mx;
  acc->n += n;
}

}  // namespace

ReplayOutcome FastReplay::evaluate(const filters::NoiseParams& noise) const {
  Pose x = initial_pose_;
  filters::Sym3 P = {initial_cov_(0, 0), initial_cov_(0, 1), initial_cov_(0, 2),
                     initial_cov_(1, 1), initial_cov_(1, 2), initial_cov_(2, 2)};
  ErrorAccumulator acc;
  ReplayOutcome out;
  for (const Segment& seg : segments_) {
    const double c = std::cos(x(2)), s = std::sin(x(2));
    const int n = seg.eval_end - seg.eval_begin;
    if (n > 0)
      accumulate_errors(ox_.data() + seg.eval_begin, oy_.data() + seg.eval_begin, gx_.data() + seg.eval_begin,
                        gy_.data() + seg.eval_begin, n, x(0), x(1), c, s, &acc);
    if (seg.has_fix) {
      out.divergence = std::isnan(seg.fix_var_x_m2)
                           ? filters::advance_segment(noise, seg.moments, seg.fix, c, s, &x, &P)
                           : filters::advance_segment(noise, seg.moments, seg.fix, seg.fix_var_x_m2,
                                                      seg.fix_var_y_m2, c, s, &x, &P);
      if (out.divergence != Divergence::none) break;
    }
  }
  out.metrics = acc.metrics();
  return out;
}

}  // namespace odotune::objectives
