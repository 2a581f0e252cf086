// The tuning objective: noise model × one or more tracks × fitness mode → a
// scalar to minimise, over the model's parameter space. A plain struct in the
// pagmo2 sense: `fitness(x) const` and `bounds()`; the optimiser sees only the
// box and never the filter.
//
// Several tracks: the fitness is the mean of the per-track fitness values, so
// every track weighs the same whatever its length. Modes 1..7 replay against
// ground truth (FastReplay); modes 8 and 9 cross-validate over the fixes
// (FixCvReplay), for tracks without ground truth.
// Divergence: a replay that diverges (non-finite state, covariance not
// positive definite) scores kDivergencePenalty and is counted by reason;
// nothing is thrown (an exception must never cross an optimiser).
#pragma once

#include <atomic>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include <odotune/objectives/fix_cv_replay.h>
#include <odotune/objectives/param_space.h>
#include <odotune/objectives/replay.h>

namespace odotune::objectives {

inline constexpr double kDivergencePenalty = 1e6;  // [m], far above any real error

struct DivergenceCounts {
  long non_finite = 0;
  long covariance_not_pd = 0;
  long total() const { return non_finite + covariance_not_pd; }
};

class EkfObjective {
 public:
  // `tracks` must outlive the objective. `mode` against ground truth.
  EkfObjective(std::vector<const FastReplay*> tracks, filters::NoiseModel model, FitnessMode mode);
  // Without ground truth: `mode` 8 or 9 over fix cross-validation replays
  // (which must outlive the objective).
  static EkfObjective over_fixes(std::vector<const FixCvReplay*> tracks, filters::NoiseModel model,
                                 FitnessMode mode);

  double fitness(std::span<const double> x) const;
  std::pair<std::vector<double>, std::vector<double>> bounds() const { return space_.box(); }

  const ParamSpace& space() const { return space_; }
  FitnessMode mode() const { return mode_; }
  long evaluations() const { return counters_->evaluations.load(); }
  DivergenceCounts divergences() const;

 private:
  EkfObjective(filters::NoiseModel model, FitnessMode mode)
      : space_(ParamSpace::for_model(model)), mode_(mode) {}
  struct Counters {
    std::atomic<long> evaluations{0};
    std::atomic<long> non_finite{0};
    std::atomic<long> covariance_not_pd{0};
  };
  std::vector<const FastReplay*> tracks_;
  std::vector<const FixCvReplay*> cv_tracks_;
  ParamSpace space_;
  FitnessMode mode_;
  std::shared_ptr<Counters> counters_ = std::make_shared<Counters>();
};

}  // namespace odotune::objectives
