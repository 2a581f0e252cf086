#include <odotune/objectives/fix_cv_replay.h>

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/why.h>

namespace odotune::objectives {

using filters::Divergence;
using filters::Pose;
using filters::Sym3;

bool FixCvOptions::IsValid(std::string* why) const {
  if (folds < 2) {
    return core::invalid(why, fmt::format("folds = {}: at least 2 (one held out, the rest applied)", folds));
  }
  if (!(std::isfinite(block_s) && block_s > 0.0)) {
    return core::invalid(why, fmt::format("block_s = {}: a finite number of seconds > 0", block_s));
  }
  return true;
}

FixCvReplay::FixCvReplay(const ReplayInput& in, const FixCvOptions& options)
    : name_(in.track_name), options_(options), initial_pose_(in.initial_pose), initial_cov_(in.initial_cov) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("FixCvOptions: " + why);
  std::vector<filters::WheelTravel> steps;
  std::vector<double> yaw;
  for (const ReplayRow& row : in.rows) {
    if (row.step >= 0) {
      steps.push_back(in.steps[static_cast<std::size_t>(row.step)]);
      yaw.push_back(in.abs_yaw_rate_rad_s[static_cast<std::size_t>(row.step)]);
    }
    if (row.fix < 0) continue;
    const auto f = static_cast<std::size_t>(row.fix);
    Segment seg;
    seg.moments = filters::reduce_segment(steps, yaw, in.wheel_base_m);
    seg.fix = in.fixes[f];
    seg.var_x_m2 = in.fix_var_x_m2[f];
    seg.var_y_m2 = in.fix_var_y_m2[f];
    const auto block = static_cast<long>(std::floor((row.t_s - in.t0_s) / options.block_s));
    seg.fold = static_cast<int>(block % options.folds);
    segments_.push_back(seg);
    steps.clear();
    yaw.clear();
  }
  const auto folds = static_cast<std::size_t>(options.folds);
  std::vector<long> held(folds, 0), applied(folds, 0);
  for (const Segment& seg : segments_)
    for (std::size_t k = 0; k < folds; ++k) (seg.fold == static_cast<int>(k) ? held : applied)[k]++;
  for (std::size_t k = 0; k < folds; ++k) {
    if (held[k] < 2 || applied[k] < 2)
      throw std::invalid_argument(fmt::format(
          "track '{}': fold {} of {} holds out {} fixes and applies {}; fix cross-validation needs at least 2 "
          "of each (a longer track, more fixes, or a shorter block than {} s)",
          name_, k + 1, options.folds, held[k], applied[k], options.block_s));
    heldout_ += held[k];
  }
}

FixCvOutcome FixCvReplay::evaluate(const filters::NoiseParams& noise) const {
  constexpr double kLog2Pi = 1.8378770664093453;  // log 2π
  FixCvOutcome out;
  ErrorAccumulator acc;
  double nll = 0.0, nis = 0.0;
  for (int fold = 0; fold < options_.folds; ++fold) {
    Pose x = initial_pose_;
    Sym3 P = {initial_cov_(0, 0), initial_cov_(0, 1), initial_cov_(0, 2),
              initial_cov_(1, 1), initial_cov_(1, 2), initial_cov_(2, 2)};
    for (const Segment& seg : segments_) {
      const double c = std::cos(x(2)), s = std::sin(x(2));
      const double qx = std::isnan(seg.var_x_m2) ? noise.q_x_m2 : seg.var_x_m2;
      const double qy = std::isnan(seg.var_y_m2) ? noise.q_y_m2 : seg.var_y_m2;
      if (seg.fold != fold) {
        out.divergence = filters::advance_segment(noise, seg.moments, seg.fix, qx, qy, c, s, &x, &P);
        if (out.divergence != Divergence::none) return out;
        continue;
      }
      filters::predict_over_segment(noise, seg.moments, c, s, &x, &P);
      // P's unique entries: xx, xy, xθ, yy, yθ, θθ.
      const double ex = seg.fix(0) - x(0), ey = seg.fix(1) - x(1);
      const double s11 = P[0] + qx, s12 = P[1], s22 = P[3] + qy;
      const double det = s11 * s22 - s12 * s12;
      if (!(det > 0.0) || !std::isfinite(ex) || !std::isfinite(ey)) {
        out.divergence = std::isfinite(det) ? Divergence::covariance_not_pd : Divergence::non_finite;
        return out;
      }
      const double m = (s22 * ex * ex - 2.0 * s12 * ex * ey + s11 * ey * ey) / det;
      acc.add(std::hypot(ex, ey));
      nis += m;
      nll += 0.5 * m + 0.5 * std::log(det) + kLog2Pi;
    }
  }
  out.heldout = acc.metrics();
  const double n = static_cast<double>(acc.n);
  out.nll = nll / n;
  out.nis = nis / n;
  return out;
}

}  // namespace odotune::objectives
