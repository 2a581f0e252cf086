// Scoring an EKF without ground truth: cross-validation over the position
// fixes (fitness modes 8 and 9, odotune/objectives/metrics.h).
//
// The fixes are split into K folds by time block: a fix at time t belongs to
// fold ⌊(t − t₀)/block⌋ mod K (with the default 1 s blocks, interleaved), so
// the filter predicts each held-out fix from the others around it, as it
// runs between fixes in use. For
// each fold the filter runs over the track applying every other fix; at each
// held-out fix z (variance R: the fix's own, aps_var_x/aps_var_y, else the
// noise model's Q) it is compared with the filter's prediction x̂ at that
// instant, covariance P:
//   e = z − x̂ (prediction error, mode 8 scores its RMSE over all folds);
//   S = P_xy + R, −log p(z) = ½ eᵀS⁻¹e + ½ log det S + log 2π (mode 9 scores
//   its mean: the predictive likelihood rewards a filter whose uncertainty is
//   right, not only its estimate); NIS = eᵀS⁻¹e (mean 2 when consistent, for
//   reports).
// Why this scores what ground truth would: with fix noise independent of the
// filter, E|z − x̂|² = E|x − x̂|² + tr R, so the noise that minimises the
// held-out prediction error also minimises the true error, up to a constant.
//
// Like FastReplay, the track is reduced to segments once (filters/
// ekf_segments.h: every fix, applied or held out, ends a segment; the folds
// share them), and evaluate() is const, allocation-free and thread-safe.
#pragma once

#include <string>
#include <vector>

#include <odotune/filters/ekf.h>
#include <odotune/filters/ekf_segments.h>
#include <odotune/objectives/metrics.h>
#include <odotune/objectives/replay_input.h>

namespace odotune::objectives {

struct FixCvOptions {
  int folds = 5;
  // [s] fixes of one block are held out together. 1 s (each fix of a 1 Hz
  // source its own block, folds interleaved) was chosen on seeds 101-102 of
  // reproduce/fix-cv-study.sh over 3 s and 10 s: longer blocks score the filter
  // on long gaps it does not have in use, and picked noise up to 1.9× worse.
  double block_s = 1.0;

  bool IsValid(std::string* why) const;
};

struct FixCvOutcome {
  ErrorMetrics heldout;  // |z − x̂| over every held-out fix [m]
  double nll = 0.0;      // mean −log predictive likelihood per held-out fix [nats]
  double nis = 0.0;      // mean normalised innovation squared
  filters::Divergence divergence = filters::Divergence::none;
};

// The scalar fitness mode 8 or 9 minimises: the held-out RMSE [m] or the
// mean −log likelihood [nats]; std::logic_error for a ground-truth mode.
inline double fix_cv_fitness(const FixCvOutcome& o, FitnessMode mode) {
  if (mode == FitnessMode::fix_rmse) return o.heldout.rmse_m;
  if (mode == FitnessMode::fix_nll) return o.nll;
  throw std::logic_error("fix_cv_fitness: mode " + std::to_string(number(mode)) + " scores ground truth");
}

class FixCvReplay {
 public:
  // Throws std::invalid_argument for invalid options or fewer than two fixes
  // per fold.
  FixCvReplay(const ReplayInput& in, const FixCvOptions& options);

  FixCvOutcome evaluate(const filters::NoiseParams& noise) const;

  const std::string& track_name() const { return name_; }
  long heldout_fixes() const { return heldout_; }
  const FixCvOptions& options() const { return options_; }

 private:
  struct Segment {
    filters::SegmentMoments moments;
    filters::Position fix = filters::Position::Zero();
    double var_x_m2 = 0.0, var_y_m2 = 0.0;  // NaN: the model's Q
    int fold = 0;                           // held out in this fold, applied in the others
  };
  std::string name_;
  FixCvOptions options_;
  filters::Pose initial_pose_;
  filters::StateCov initial_cov_;
  // One segment per fix, shared by every fold (a fix ends a segment whether
  // it is applied or held out).
  std::vector<Segment> segments_;
  long heldout_ = 0;
};

}  // namespace odotune::objectives
