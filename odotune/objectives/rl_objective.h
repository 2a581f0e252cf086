// Tuning robot_localization's EKF on a robot's own recording, without ground
// truth: the filter as the node runs it (odotune/rlnode/replay.h), scored by how well
// it predicts GPS fixes it was not given (odotune/objectives/rl_protocols.h says which).
//
//   heldout_fixes  fitness mode 8 on this filter: K folds of time blocks; per
//                  fold the other fixes are fused and the filter's prediction
//                  at each held-out fix is scored; RMSE over all folds [m].
//   outage         simulated GPS outages: windows of each length L starting
//                  every few seconds across the span, each its own replay with
//                  the GPS fused before it; RMSE over every window's fixes [m].
//   both           the sum of the two RMSEs, each divided by its value for the
//                  parameter file's own settings (so neither dominates by scale).
//
// With `keep_heldout`, normal operation is not traded for outages: a
// candidate whose held-out-fix RMSE exceeds the file's scores above the file's
// own fitness. A weak prior (`prior_weight`) pulls factors the data leave
// free toward the file's values: it adds prior_weight · mean((log10 factor)²).
//
// The search space (BoxSpace, log10): multipliers of the file's process noise,
// per diagonal entry that the configuration can move or per block (position,
// orientation, linear velocity, angular velocity, acceleration), and
// optionally of each input's message covariance (advice for the robot: the
// node reads covariances from its messages). fitness() is const and
// thread-safe; the schedules are laid out once.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <odotune/objectives/box_space.h>
#include <odotune/objectives/rl_protocols.h>
#include <odotune/rlnode/recording.h>
#include <odotune/rlnode/replay.h>

namespace odotune::objectives {

// heldout_fixes, outage and both as above; the others are the innovation
// statistics of odotune/objectives/rl_innovations.h (innovation-nll, nis, whiteness:
// of the fused fixes over the span; heldout-nll: of the held-out folds).
enum class RlFitness { heldout_fixes, outage, both, innovation_nll, nis, whiteness, heldout_nll };
inline constexpr std::array<RlFitness, 7> kAllRlFitnesses = {
    RlFitness::heldout_fixes, RlFitness::outage,    RlFitness::both,       RlFitness::innovation_nll,
    RlFitness::nis,           RlFitness::whiteness, RlFitness::heldout_nll};
// "heldout-fixes", "outage", "both", "innovation-nll", "nis", "whiteness", "heldout-nll"
std::string_view to_string(RlFitness f);
bool parse_rl_fitness(std::string_view text, RlFitness* out);  // false (out untouched) for other text

// The fitness mode a results store records for each (odotune/results/run_record.h):
// held-out fixes is mode 8 on this filter too; the others have numbers of their own.
constexpr int kRlHeldoutFixesMode = 8, kRlOutageMode = 10, kRlBothMode = 11, kRlInnovationNllMode = 12,
              kRlNisMode = 13, kRlWhitenessMode = 14, kRlHeldoutNllMode = 15;
int stored_mode(RlFitness f);
std::optional<RlFitness> rl_fitness_of_mode(int mode);

enum class RlNoiseSpace { diagonal, blocks };
inline constexpr std::array<RlNoiseSpace, 2> kAllRlNoiseSpaces = {RlNoiseSpace::diagonal, RlNoiseSpace::blocks};
std::string_view to_string(RlNoiseSpace s);  // "diagonal", "blocks"
bool parse_rl_noise_space(std::string_view text, RlNoiseSpace* out);

// The process-noise parameters of a space ("q_x" … per diagonal entry, or
// "q_position" … per block), without the entries two_d_mode forces.
std::vector<std::string> rl_noise_parameter_names(RlNoiseSpace space, bool two_d);
// The diagonal entries the parameter `name` scales; empty for a name that is
// not a process-noise parameter.
std::vector<int> rl_noise_members(std::string_view name, bool two_d);
// Applies tuned factors by name (process-noise parameters as above, and
// "cov_<sensor>" on an input's message covariance) to *s, which holds the
// file's own settings (rlnode::settings_of). False with *why for an unknown
// name, a factor that is not positive and finite, or lists of unequal length.
// The UKF constants' factors in a tune's space, in this order: alpha,
// n + kappa (n = 15, so kappa stays above −n) and beta.
inline constexpr std::array<std::string_view, 3> kUkfFactorNames = {"ukf_alpha", "ukf_n_plus_kappa",
                                                                    "ukf_beta"};
// The constants with the factors applied to `base`.
filters::rl::UkfConstants scaled_ukf_constants(const filters::rl::UkfConstants& base, double alpha_factor,
                                               double n_plus_kappa_factor, double beta_factor);

bool apply_rl_factors(const rlnode::RlParams& params, std::span<const std::string> names,
                      std::span<const double> factors, rlnode::ReplaySettings* s, std::string* why);

struct RlTuneOptions {
  RlFitness fitness = RlFitness::both;
  RlNoiseSpace space = RlNoiseSpace::diagonal;
  bool input_covariances = true;  // also search a factor on each input's message covariance
  // Also search factors on ukf_node's alpha, n + kappa and beta (n = 15):
  // kUkfFactorNames; a file that runs ekf_node is refused.
  bool ukf_constants = false;
  int folds = 5;                                // heldout_fixes
  double block_s = 1.0;                         // heldout_fixes: fixes of one block are held out together [s]
  std::vector<double> outage_s = {30.0, 60.0};  // outage: the windows' lengths L [s]
  double outage_stride_s = 10.0;                // outage: a window of each length starts every … [s]
  double warmup_s = 30.0;                       // outage: the GPS fused this long before the first window [s]
  bool keep_heldout = true;  // a candidate worse at held-out fixes than the file scores above it
  // Score the held-out fixes and the outages by error_without_fix_noise_m
  // (below) instead of their RMSE: for fixes whose variances describe them.
  bool subtract_fix_variance = false;
  double prior_weight = 0.0;  // ≥ 0: the prior toward the file's values (above)
  // Multipliers in [10^−down, 10^up]. The Husky's first-half tune ended on
  // both edges of [1e-4, 1e2], so the box spans ten decades.
  double decades_down = 6.0, decades_up = 4.0;
  // Only the recording before this time (stamps, absolute [ns]) is used.
  std::int64_t until_ns = std::numeric_limits<std::int64_t>::max();

  bool IsValid(std::string* why) const;
};

// Held-out fix errors of one or more replays.
struct FixScore {
  double rmse_m = 0.0, mae_m = 0.0, maxe_m = 0.0;  // of the horizontal error at the scored fixes
  long fixes = 0;
  bool finite = true;
  double fix_var_m2 = 0.0;  // the mean over the scored fixes of their var_x + var_y [m²]
};
// The filter's RMS error at the scored fixes with the fixes' own noise taken
// out, √max(rmse² − fix_var, 0) [m]. A fix withheld from the filter has noise
// independent of the prediction, so E|x̂ − z|² = E|x̂ − x|² + tr R: this
// estimates the error against the true position, where the fixes'
// covariances are their true ones.
double error_without_fix_noise_m(const FixScore& s);
FixScore score_of(std::span<const rlnode::ReplayOutput> outputs);
// `s` replayed over each schedule, its held-out fixes scored together.
FixScore replay_score(const rlnode::Recording& rec, std::span<const rlnode::Schedule> schedules,
                      const rlnode::ReplaySettings& s);
// The same for each of `settings`, replayed in lock step (rlnode::replay_batch):
// each identical to its replay_score, bit for bit.
std::vector<FixScore> replay_score_batch(const rlnode::Recording& rec,
                                         std::span<const rlnode::Schedule> schedules,
                                         std::span<const rlnode::ReplaySettings> settings);

// The outage fitness's windows, replayed from one run that fuses every fix:
// each window's replay continues from a copy of that run taken where the
// two schedules part.
class OutageReplays {
 public:
  OutageReplays() = default;
  OutageReplays(const rlnode::Recording& rec, std::span<const OutageWindow> windows, std::int64_t until_ns);
  // Every window's scored fixes under `s`, together.
  FixScore score(const rlnode::ReplaySettings& s) const;
  // score() of each of `settings`, in lock step (rlnode::BatchReplayer), bit for bit.
  std::vector<FixScore> score_batch(std::span<const rlnode::ReplaySettings> settings) const;
  std::size_t windows() const { return tails_.size(); }
  // Each window's replay under `s`, its trajectory kept from where it parts
  // from the fused run (the window's first withheld fix) to the window's end.
  void each_window(const rlnode::ReplaySettings& s,
                   const std::function<void(const OutageWindow&, const rlnode::ReplayOutput&)>& f,
                   bool keep_trajectory = true) const;

 private:
  struct Tail {
    std::size_t shared = 0;             // events of fused_ the window's replay shares
    std::vector<rlnode::Event> events;  // its own events after them
    OutageWindow window;
  };
  const rlnode::Recording* rec_ = nullptr;
  rlnode::Schedule fused_;
  std::vector<Tail> tails_;  // by `shared`
};

// Scores of several recordings as one: the RMSE and MAE over all their fixes
// together, the largest error, finite when each recording that scored a fix is.
// One score is returned as it is.
FixScore pooled(std::span<const FixScore> scores);
namespace detail {
// An RMS score's parts (samples, RMSE, MAE, largest error, finite), pooled as above.
struct RmsPart {
  long n = 0;
  double rmse = 0.0, mae = 0.0, max = 0.0;
  bool finite = true;
  double mean = 0.0;  // a per-sample quantity averaged with them (FixScore::fix_var_m2)
};
RmsPart pooled_parts(std::span<const RmsPart> parts);
}  // namespace detail

class RlObjective {
 public:
  // Lays out both parts' schedules and scores `base` on them. Throws
  // std::invalid_argument for invalid options, a recording without GPS fixes,
  // or a part the fitness uses that scores no fix before `until_ns`.
  RlObjective(const rlnode::Recording& rec, const rlnode::ReplaySettings& base, const RlTuneOptions& options);
  // Several recordings of one robot under one parameter file (their
  // RlParams alike but for the initial state), tuned jointly: each part's
  // fixes pooled over all of them (pooled()). The innovation statistics take
  // one recording only (std::invalid_argument otherwise). The recordings
  // must outlive the objective.
  RlObjective(std::span<const rlnode::Recording* const> recs, rlnode::ReplaySettings base,
              const RlTuneOptions& options);

  // data_fitness(x) plus the prior.
  double fitness(std::span<const double> x) const;
  // The fitness of the scores alone (what the tune reports and profiles).
  double data_fitness(std::span<const double> x) const;
  // Both for out.size() points one after the other in xs, replayed in lock
  // step: each value identical to the single call's, bit for bit
  // (odotune/tuner/problem.h's batch contract).
  void fitness_batch(std::span<const double> xs, std::span<double> out) const;
  void data_fitness_batch(std::span<const double> xs, std::span<double> out) const;
  int batch_size() const { return statistic_kind() ? 1 : filters::rl::kLanes; }
  std::pair<std::vector<double>, std::vector<double>> bounds() const { return space_.box(); }

  const BoxSpace& space() const { return space_; }
  rlnode::ReplaySettings settings_at(std::span<const double> x) const;
  // Per part: the held-out fixes' and the outages' scores, whether or not the
  // fitness uses them; the base settings' own, from the constructor.
  FixScore heldout_score(const rlnode::ReplaySettings& s) const;
  FixScore outage_score(const rlnode::ReplaySettings& s) const;
  const FixScore& baseline_heldout() const { return base_parts_.heldout; }
  const FixScore& baseline_outage() const { return base_parts_.outage; }
  double baseline_fitness() const { return combine(base_parts_); }
  // What a candidate is scored by: the held-out fixes and the outages (each
  // when the fitness or the guard uses it) and an innovation statistic.
  struct Parts {
    FixScore heldout, outage;
    double statistic = 0.0;
  };
  Parts parts(const rlnode::ReplaySettings& s) const;
  // The fitness of the parts (a large penalty when a used part is not finite).
  double combine(const Parts& p) const;
  // combine() with the held-out-fix guard; counts a divergence.
  double fitness_of(const Parts& p) const;
  const RlTuneOptions& options() const { return options_; }
  std::size_t window_count() const;
  // fitness() calls whose replay diverged (scored as a penalty), so far.
  long diverged() const { return diverged_->load(); }

 private:
  // One recording's schedules.
  struct Replays {
    const rlnode::Recording* rec = nullptr;
    std::vector<rlnode::Schedule> heldout;
    rlnode::Schedule fused;  // every fix fused over the span: the innovation statistics
    OutageReplays outages;
  };
  std::vector<Replays> recs_;
  rlnode::ReplaySettings base_;
  RlTuneOptions options_;
  BoxSpace space_;
  std::vector<std::vector<int>> noise_members_;  // per noise parameter: the diagonal entries it scales
  std::vector<int> cov_sensors_;                 // per covariance parameter: the sensor
  Parts base_parts_;
  std::unique_ptr<std::atomic<long>> diverged_ = std::make_unique<std::atomic<long>>(0);

  // Refuses, in one line, base scores there is nothing to tune from: no
  // outage window, a file whose own filter diverges, no fix scored.
  void check_base_scores(const rlnode::Recording& rec) const;
  bool heldout_needed() const;
  bool outage_needed() const;
  bool statistic_kind() const;
  double error_m(const FixScore& s) const;  // the RMSE, or without the fixes' noise (the options)
  double prior(std::span<const double> x) const;
};

}  // namespace odotune::objectives
