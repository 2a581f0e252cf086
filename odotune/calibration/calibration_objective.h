// Tuning the particle-filter calibrator's own settings: the
// N_eff threshold fraction, the max-weight threshold, α of the adaptive
// process noise (Fariña, Toledo & Acosta, RA-L 2026, eq. 11), the particles
// per unit of radius dispersion (§V) and the random-walk σ form a named,
// bounded, log-scaled space; the objective runs the calibrator over tracks
// whose truth is known and scores calibration quality and cost. A plain
// struct in the pagmo2 sense (`fitness(x) const`, `bounds()`), so `tune` and
// `grid` search it with the same PSO/NLopt solvers as the EKF noise models.
//
// Score per track (lower is better), a weighted sum of terms that are each
// about 1 for a poor calibration and 0 for a perfect free one:
//   w_radius · e_R / 0.5 %          e_R: mean |R̂ − R|/R of both radii at the track's end
//   + w_convergence · c             c: convergence time / track duration (1: never)
//   + w_pose · RMSE_xy / (0.5 % of L)   calibrated odometry's pose RMSE against
//                                   ground truth, L the ground-truth path length
//   + w_cost · N̄ / 8000             N̄: mean particle count per iteration
// The cost term counts particles, not milliseconds, so the fitness is a pure
// function of x (same seed ⇒ same score on any machine or thread count). A
// track without truth parameters contributes only the pose and cost terms.
// (The pose term is scaled by the path, not by the nominal odometry's error:
// that can be metres, which made the term too flat to matter.) The fitness
// is the mean over tracks. A calibrator that fails (non-finite estimate)
// scores kCalibrationPenalty and is counted; nothing is thrown.
#pragma once

#include <atomic>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <odotune/calibration/calibration_input.h>
#include <odotune/calibration/calibration_run.h>
#include <odotune/objectives/box_space.h>

namespace odotune::calibration {

inline constexpr double kCalibrationPenalty = 1e3;

// The tuned settings, in the space's order and units:
//   neff_fraction (-), max_weight_ratio (-), alpha (m per m/s),
//   dispersion_per_particle_mm (mm), random_walk_sigma_mm (mm).
objectives::BoxSpace calibration_space();
// Physical values (calibration_space() order and units) applied to `base`.
filters::PfCalibratorParams apply_calibration_params(const filters::PfCalibratorParams& base,
                                                     std::span<const double> physical);
// `params`' values of the tuned settings, in calibration_space() order.
std::vector<double> calibration_params_of(const filters::PfCalibratorParams& params);

struct CalibrationScoreWeights {
  double radius = 1.0, convergence = 1.0, pose = 1.0, cost = 0.25;
  bool IsValid(std::string* why) const;
};

// The score of one finished calibration of `inputs` (see the file comment).
double calibration_score(const CalibrationResult& result, const std::vector<const CalibrationInput*>& inputs,
                         const CalibrationScoreWeights& weights);

class CalibrationObjective {
 public:
  // `inputs` must outlive the objective. `base` carries the fixed choices
  // (resampler, policy, ranges, initial particle count, seed); the PF always
  // runs single-threaded inside fitness() (the solver parallelises over its
  // own particles). `adaptive` selects the adaptive PF.
  CalibrationObjective(std::vector<const CalibrationInput*> inputs, filters::PfCalibratorParams base,
                       bool adaptive, CalibrationScoreWeights weights = {});

  double fitness(std::span<const double> x) const;
  std::pair<std::vector<double>, std::vector<double>> bounds() const { return space_.box(); }

  const objectives::BoxSpace& space() const { return space_; }
  // The full calibration run at box point x (what fitness() scores).
  CalibrationResult run(std::span<const double> x) const;
  long evaluations() const { return counters_->evaluations.load(); }
  long failures() const { return counters_->failures.load(); }

 private:
  struct Counters {
    std::atomic<long> evaluations{0};
    std::atomic<long> failures{0};
  };
  std::vector<const CalibrationInput*> inputs_;
  filters::PfCalibratorParams base_;
  bool adaptive_;
  CalibrationScoreWeights weights_;
  objectives::BoxSpace space_;
  std::shared_ptr<Counters> counters_ = std::make_shared<Counters>();
};

}  // namespace odotune::calibration
