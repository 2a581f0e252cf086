// One tuning run: noise model × tracks × fitness mode × solver × seed →
// tuned parameters, with baseline and tuned metrics from the reference replay.
// Computation only: no parsing, no printing (the commands do those), so the
// experiment grid can run many of these side by side.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <odotune/calibration/calibration_input.h>
#include <odotune/filters/ekf_noise.h>
#include <odotune/learned/fusion_input.h>
#include <odotune/objectives/box_space.h>
#include <odotune/objectives/ekf_objective.h>
#include <odotune/objectives/metrics.h>
#include <odotune/objectives/replay.h>
#include <odotune/tracks/track.h>
#include <odotune/tuner/problem.h>
#include <odotune/tuner/solver_choice.h>
#include <odotune/tuner/summary.h>

namespace odotune::jobs {

struct RlLoaded;  // odotune/jobs/rl_job.h

// A track prepared for replay: the reference input and its fast form; and,
// when a calibrator model is tuned on it (grid), its calibration input; when
// the fusion UKF is (grid), its fusion input. Each part is built only when a
// model needs it: `fast` is null for a track prepared for calibrators or the
// UKF only.
struct PreparedTrack {
  std::string name;
  objectives::ReplayInput input;
  std::unique_ptr<objectives::FastReplay> fast;
  // Fix cross-validation (modes 8 and 9): its folds, replayed from the first
  // fix. For a track without ground truth `input` is that replay's (from the
  // first fix) and `fast` is null.
  std::unique_ptr<objectives::FixCvReplay> cv;
  std::optional<calibration::CalibrationInput> calibration;
  std::optional<learned::FusionInput> fusion;
  // A bag with robot_localization's parameter file (model rl-ekf, grid; odotune/jobs/rl_job.h).
  std::shared_ptr<const RlLoaded> rl;
};
// Throws std::invalid_argument (one line naming the track) when it cannot be
// replayed or has no position fixes (nothing to tune).
PreparedTrack prepare_track(const tracks::Track& track);
// The same, ready for fix cross-validation (modes 8 and 9) too: `cv` holds
// its folds (from the first fix, ReplayReference::fixes); a track with ground
// truth keeps its ground-truth `input` and `fast` (for modes 1..7 and to
// report the error a fix-tuned noise makes), one without gets the
// first-fix input and no `fast`.
PreparedTrack prepare_track_fix_cv(const tracks::Track& track, const objectives::FixCvOptions& cv = {});

// The solver part of a tuning request, shared by the EKF (TuneRequest) and
// the calibrator tunes (calibration_tune_job.h), which both extend it.
struct SolverSettings {
  tuner::SolverChoice solver;  // PSO by default
  std::uint64_t seed = 1;
  int particles = 50;    // PSO
  int iterations = 150;  // PSO
  long evaluations = 0;  // NLopt budget; 0 = particles × (iterations + 1)
  std::function<void(long, long)> progress;
  const std::atomic<bool>* stop = nullptr;

  // The solver's name and budget, checked as the solver itself would.
  bool IsValid(std::string* why) const;
};

struct TuneRequest : SolverSettings {
  filters::NoiseModel model = filters::NoiseModel::rq;
  objectives::FitnessMode mode =
      objectives::kDefaultFitnessMode;  // 1..7 against ground truth, 8 and 9 by fix cross-validation
};

struct TrackScore {
  std::string track;
  objectives::ErrorMetrics baseline, tuned;  // against ground truth, or (modes 8, 9) the held-out fixes
  // Modes 8 and 9: the held-out fixes' mean −log likelihood and NIS, and the
  // errors against ground truth when the track has it (never seen by the tune).
  double baseline_nll = 0.0, tuned_nll = 0.0, baseline_nis = 0.0, tuned_nis = 0.0;
  std::optional<objectives::ErrorMetrics> gt_baseline, gt_tuned;
};

struct TuneOutcome {
  TuneRequest request;
  std::vector<std::string> param_names;
  std::vector<std::string> param_units;
  std::vector<double> params;  // physical values, in param_units
  filters::NoiseParams noise;  // the same, as filter noise (SI)
  std::vector<TrackScore> tracks;
  objectives::ErrorMetrics baseline_mean, tuned_mean;  // means over tracks
  double baseline_fitness = 0, tuned_fitness = 0;
  objectives::DivergenceCounts divergences;
  tuner::Summary summary;           // evaluations, seconds, termination, log
  bool against_fixes = false;       // modes 8, 9: the metrics are of the held-out fixes
  objectives::FixCvOptions fix_cv;  // ... and their folds
  std::string note;                 // how the mode was chosen, when the command chose it
};

// An objective as the tuner sees it: a box and a function (objectives/ does
// not depend on tuner/, so the adapter lives here). `Objective` has
// fitness(x) const and bounds() → (lower, upper); it must outlive this.
template <typename Objective>
struct BoxProblem {
  const Objective* objective;
  double fitness(std::span<const double> x) const { return objective->fitness(x); }
  tuner::Bounds bounds() const {
    auto [lo, hi] = objective->bounds();
    return {lo, hi};
  }
};

// The same for an objective that also evaluates a batch of points in one
// call (odotune/tuner/problem.h's BatchProblem).
template <typename Objective>
  requires requires(const Objective& o, std::span<const double> xs, std::span<double> out) {
    o.fitness_batch(xs, out);
    o.batch_size();
  }
struct BoxProblem<Objective> {
  const Objective* objective;
  double fitness(std::span<const double> x) const { return objective->fitness(x); }
  void fitness_batch(std::span<const double> xs, std::span<double> out) const {
    objective->fitness_batch(xs, out);
  }
  int batch_size() const { return objective->batch_size(); }
  tuner::Bounds bounds() const {
    auto [lo, hi] = objective->bounds();
    return {lo, hi};
  }
};

// Minimises `problem` with PSO or NLopt as `s` says (NLopt from x0 when given,
// else its default start). Throws std::runtime_error when the solver fails.
tuner::Summary run_solver(tuner::ProblemRef problem, const SolverSettings& s, std::vector<double> x0 = {});

// A tune that starts from known defaults (the calibrator and UKF tunes): the
// solver from the defaults' box point, the defaults' own fitness by the same
// problem, and the tuned physical values — the defaults themselves when they
// score better than anything the solver found (so a tune never worsens the
// fitness on its tracks).
struct DefaultsTune {
  tuner::Summary summary;
  double baseline_fitness = 0.0, tuned_fitness = 0.0;
  bool default_kept = false;
  std::vector<double> params;                         // tuned physical values (or the defaults)
  std::vector<std::string> param_names, param_units;  // the space's
};
DefaultsTune run_solver_from_defaults(tuner::ProblemRef problem, const SolverSettings& s,
                                      const objectives::BoxSpace& space,
                                      const std::vector<double>& default_params);

// Runs the solver; throws std::invalid_argument for an invalid request and
// std::runtime_error when the solver fails.
TuneOutcome run_tune(const std::vector<const PreparedTrack*>& tracks, const TuneRequest& request);

// Mean of per-track metrics (each track weighs the same).
objectives::ErrorMetrics mean_metrics(const std::vector<objectives::ErrorMetrics>& per_track);

}  // namespace odotune::jobs
