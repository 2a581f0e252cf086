#include <odotune/calibration/calibration_objective.h>

#include <cmath>
#include <stdexcept>

#include <odotune/core/why.h>

namespace odotune::calibration {

namespace {

constexpr double kMmToM = 1e-3;
constexpr double kRadiusTolerance = 0.005;      // the paper's 0.5 % convergence band
constexpr double kReferenceParticles = 8000.0;  // the adaptive PF's initial count (§V)

enum CalibrationParam : std::size_t {
  kNeffFraction = 0,
  kMaxWeightRatio = 1,
  kAlpha = 2,
  kDispersionPerParticle = 3,
  kRandomWalkSigma = 4,
  kCalibrationDim = 5
};

constexpr double kPoseTolerance = 0.005;  // pose RMSE scale: 0.5 % of the path length

double relative_error(double estimate, double truth) { return std::abs(estimate - truth) / truth; }

// Length of the ground-truth path [m] (0 without ground truth).
double gt_path_length_m(const CalibrationInput& in) {
  double length = 0.0, px = std::nan(""), py = std::nan("");
  for (std::size_t i = 0; i < in.gt_x.size(); ++i) {
    if (!std::isfinite(in.gt_x[i]) || !std::isfinite(in.gt_y[i])) continue;
    if (std::isfinite(px)) length += std::hypot(in.gt_x[i] - px, in.gt_y[i] - py);
    px = in.gt_x[i];
    py = in.gt_y[i];
  }
  return length;
}

}  // namespace

objectives::BoxSpace calibration_space() {
  // Bounds: a decade or more either side of the paper's values (N_th = 0.5·N,
  // α = 1e-4, one particle per 0.01 mm, σ = 0.5 mm).
  return objectives::BoxSpace({
      {"neff_fraction", "-", 0.05, 1.0, false, "resample when N_eff < fraction·N (policy neff)"},
      {"max_weight_ratio", "-", 1.0, 1000.0, true, "resample when the largest weight < ratio/N (policy max)"},
      {"alpha", "m/(m/s)", 1e-6, 1e-1, true,
       "adaptive random-walk σ per unit of velocity disagreement (eq. 11)"},
      {"dispersion_per_particle_mm", "mm", 1e-3, 1.0, true,
       "radius dispersion per particle of the adaptive count (§V: 0.01 mm)"},
      {"random_walk_sigma_mm", "mm", 1e-3, 5.0, true, "random-walk σ of R_R, R_L, D per iteration (plain PF)"},
  });
}

filters::PfCalibratorParams apply_calibration_params(const filters::PfCalibratorParams& base,
                                                     std::span<const double> v) {
  if (v.size() != kCalibrationDim) throw std::invalid_argument("calibration params: wrong dimension");
  filters::PfCalibratorParams p = base;
  // The space is the paper's PF settings (its walk σ, α, ...): tuned under
  // the paper's evolution, which they drive (the evidence evolution has no
  // walk σ to tune, odotune/filters/pf_evolution.h).
  p.evolution = filters::PfEvolution::paper;
  p.neff_fraction = v[kNeffFraction];
  p.max_weight_ratio = v[kMaxWeightRatio];
  p.alpha = v[kAlpha];
  p.dispersion_per_particle_m = v[kDispersionPerParticle] * kMmToM;
  p.random_walk_sigma_m = v[kRandomWalkSigma] * kMmToM;
  return p;
}

std::vector<double> calibration_params_of(const filters::PfCalibratorParams& p) {
  return {p.neff_fraction, p.max_weight_ratio, p.alpha, p.dispersion_per_particle_m / kMmToM,
          p.random_walk_sigma_m / kMmToM};
}

bool CalibrationScoreWeights::IsValid(std::string* why) const {
  const std::pair<const char*, double> all[] = {
      {"radius", radius}, {"convergence", convergence}, {"pose", pose}, {"cost", cost}};
  for (const auto& [name, w] : all)
    if (!std::isfinite(w) || w < 0.0) {
      return core::invalid(why, std::string("score weight ") + name + " = " + std::to_string(w) +
                                    " must be a finite number ≥ 0");
    }
  return true;
}

double calibration_score(const CalibrationResult& result, const std::vector<const CalibrationInput*>& inputs,
                         const CalibrationScoreWeights& w) {
  if (result.tracks.size() != inputs.size())
    throw std::invalid_argument("calibration_score: the result's tracks and the inputs differ in number");
  double total = 0.0;
  const double cost = result.mean_particles / kReferenceParticles;
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    const TrackCalibrationScore& s = result.tracks[k];
    double score = w.cost * cost;
    const double path_m = gt_path_length_m(*inputs[k]);
    if (std::isfinite(s.pose_rmse_m) && path_m > 0.0)
      score += w.pose * s.pose_rmse_m / (kPoseTolerance * path_m);
    if (s.truth_final) {
      const double e_r =
          0.5 * (relative_error(s.final_params.wheel_radius_left_m, s.truth_final->wheel_radius_left_m) +
                 relative_error(s.final_params.wheel_radius_right_m, s.truth_final->wheel_radius_right_m));
      const auto& t = inputs[k]->t;
      const double duration = t.size() > 1 ? t.back() - t.front() : 0.0;
      const double c = (s.convergence_time_s && duration > 0.0)
                           ? std::min(1.0, *s.convergence_time_s / duration)
                           : 1.0;
      score += w.radius * e_r / kRadiusTolerance + w.convergence * c;
    }
    total += score;
  }
  return total / static_cast<double>(inputs.size());
}

CalibrationObjective::CalibrationObjective(std::vector<const CalibrationInput*> inputs,
                                           filters::PfCalibratorParams base, bool adaptive,
                                           CalibrationScoreWeights weights)
    : inputs_(std::move(inputs)),
      base_(std::move(base)),
      adaptive_(adaptive),
      weights_(weights),
      space_(calibration_space()) {
  if (inputs_.empty()) throw std::invalid_argument("calibration objective: no tracks");
  std::string why;
  if (!weights_.IsValid(&why)) throw std::invalid_argument(why);
  base_.threads = 1;
  base_.adaptive = adaptive_;
  if (!base_.IsValid(&why)) throw std::invalid_argument(why);
}

CalibrationResult CalibrationObjective::run(std::span<const double> x) const {
  CalibrationOptions o;
  o.method = adaptive_ ? CalibrationMethod::adaptive_pf : CalibrationMethod::pf;
  o.pf = apply_calibration_params(base_, space_.to_physical(x));
  return run_calibration(inputs_, o);
}

double CalibrationObjective::fitness(std::span<const double> x) const {
  counters_->evaluations.fetch_add(1, std::memory_order_relaxed);
  try {
    const CalibrationResult r = run(x);
    const double f = calibration_score(r, inputs_, weights_);
    if (std::isfinite(f)) return f;
  } catch (const std::exception&) {
    // An invalid setting or a failed run is a penalty, never an exception
    // through the solver (counted below).
  }
  counters_->failures.fetch_add(1, std::memory_order_relaxed);
  return kCalibrationPenalty;
}

}  // namespace odotune::calibration
