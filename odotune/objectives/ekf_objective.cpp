#include <odotune/objectives/ekf_objective.h>

#include <cmath>
#include <stdexcept>

namespace odotune::objectives {

EkfObjective::EkfObjective(std::vector<const FastReplay*> tracks, filters::NoiseModel model, FitnessMode mode)
    : tracks_(std::move(tracks)), space_(ParamSpace::for_model(model)), mode_(mode) {
  if (tracks_.empty()) throw std::invalid_argument("EkfObjective: no tracks");
  if (is_fix_cv(mode)) throw std::invalid_argument("EkfObjective: mode must be 1..7");
}

EkfObjective EkfObjective::over_fixes(std::vector<const FixCvReplay*> tracks, filters::NoiseModel model,
                                      FitnessMode mode) {
  if (tracks.empty()) throw std::invalid_argument("EkfObjective: no tracks");
  if (!is_fix_cv(mode)) throw std::invalid_argument("EkfObjective: fix cross-validation modes are 8 and 9");
  EkfObjective o(model, mode);
  o.cv_tracks_ = std::move(tracks);
  return o;
}

double EkfObjective::fitness(std::span<const double> x) const {
  counters_->evaluations.fetch_add(1, std::memory_order_relaxed);
  const filters::NoiseParams noise = space_.to_noise(space_.to_physical(x));
  double total = 0.0;
  const std::size_t n = tracks_.empty() ? cv_tracks_.size() : tracks_.size();
  for (std::size_t i = 0; i < n; ++i) {
    ReplayOutcome out;
    double f = 0.0;
    if (tracks_.empty()) {
      const FixCvOutcome cv = cv_tracks_[i]->evaluate(noise);
      out.divergence = cv.divergence;
      f = fix_cv_fitness(cv, mode_);
    } else {
      out = tracks_[i]->evaluate(noise);
      f = fitness_of(out.metrics, mode_);
    }
    if (out.divergence == filters::Divergence::covariance_not_pd) {
      counters_->covariance_not_pd.fetch_add(1, std::memory_order_relaxed);
      return kDivergencePenalty;
    }
    if (out.divergence == filters::Divergence::non_finite || !std::isfinite(f)) {
      counters_->non_finite.fetch_add(1, std::memory_order_relaxed);
      return kDivergencePenalty;
    }
    total += f;
  }
  return total / static_cast<double>(n);
}

DivergenceCounts EkfObjective::divergences() const {
  return {counters_->non_finite.load(), counters_->covariance_not_pd.load()};
}

}  // namespace odotune::objectives
