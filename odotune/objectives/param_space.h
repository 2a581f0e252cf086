// Named, bounded parameter spaces of the three EKF noise models (Kovacs et al.
// §2.3.1–2.3.3), and their mapping to the box an optimiser sees.
//
// Bounds are the study's, in the study's units where it states them in mm
// (r1, r2, q1, q2 in mm²); SI inside (NoiseParams). A parameter whose bounds
// span two or more decades is searched in log10 space, so the optimiser's box
// coordinate is log10(value); others are searched linearly.
#pragma once

#include <span>
#include <string>
#include <utility>
#include <vector>

#include <odotune/filters/ekf_noise.h>
#include <odotune/objectives/box_space.h>

namespace odotune::objectives {

// The box mapping (params, box, to_physical, to_box) is BoxSpace's.
class ParamSpace : public BoxSpace {
 public:
  ParamSpace() = default;
  static ParamSpace for_model(filters::NoiseModel model);

  filters::NoiseModel model() const { return model_; }

  // Physical values → filter noise (SI). Values outside the bounds are
  // accepted (an exported configuration may be edited by hand) as long as
  // NoiseParams::IsValid holds.
  filters::NoiseParams to_noise(std::span<const double> physical) const;
  // Filter noise → physical values (inverse of to_noise for this model).
  std::vector<double> from_noise(const filters::NoiseParams& noise) const;

 private:
  filters::NoiseModel model_ = filters::NoiseModel::alpha;
  ParamSpace(filters::NoiseModel model, std::vector<ParamSpec> params)
      : BoxSpace(std::move(params)), model_(model) {}
};

// The untuned configuration a user would write (README, "Baseline"): position
// fixes trusted at their specified σ = 60 mm, and wheel odometry trusted to
// the common rule of thumb "odometry is good to about 1 % of the distance
// travelled": σ of each wheel's travel = 1 % of that travel, plus 1 % of the
// travel difference in turns (α1 = α2 = 0.01). The same for all three models.
filters::NoiseParams baseline_noise();

}  // namespace odotune::objectives
