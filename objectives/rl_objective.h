// Tuning robot_localization's EKF on a robot's own recording, without ground
// truth: the filter as the node runs it (rlnode/replay.h), scored by how well
// it predicts GPS fixes it was not given.
//
//   heldout_fixes  fitness mode 8 on this filter: K folds of time blocks
//                  (fold = ⌊(t − t₀)/block⌋ mod K); per fold the other fixes
//                  are fused and the filter's prediction at each held-out fix
//                  is scored; RMSE over all folds [m].
//   outage         simulated GPS outages of L s: the fixes inside each outage
//                  are withheld and the filter's prediction at them scored
//                  (RMSE [m]); the fixes between outages are fused. Outages
//                  start L/2 after the first fix and repeat every 1.5·L.
//   both           the sum of the two RMSEs, each divided by its value for the
//                  parameter file's own settings (so neither dominates by scale).
//
// The search space (BoxSpace, log10): multipliers of the file's process noise,
// per diagonal entry that the configuration can move or per block (position,
// orientation, linear velocity, angular velocity, acceleration), and
// optionally of each input's message covariance (advice for the robot: the
// node reads covariances from its messages). fitness() is const and
// thread-safe; the schedules are laid out once.
#pragma once

#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "objectives/box_space.h"
#include "rlnode/recording.h"
#include "rlnode/replay.h"

namespace odotune {

enum class RlFitness { heldout_fixes, outage, both };
std::string_view to_string(RlFitness f);                       // "heldout-fixes", "outage", "both"
bool parse_rl_fitness(std::string_view text, RlFitness* out);  // false (out untouched) for other text

// The fitness mode a results store records for each (results/run_record.h):
// held-out fixes is mode 8 on this filter too; the others have numbers of their own.
constexpr int kRlHeldoutFixesMode = 8, kRlOutageMode = 10, kRlBothMode = 11;
int stored_mode(RlFitness f);
std::optional<RlFitness> rl_fitness_of_mode(int mode);

enum class RlNoiseSpace { diagonal, blocks };
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
bool apply_rl_factors(const rlnode::RlParams& params, std::span<const std::string> names,
                      std::span<const double> factors, rlnode::ReplaySettings* s, std::string* why);

struct RlTuneOptions {
  RlFitness fitness = RlFitness::outage;
  RlNoiseSpace space = RlNoiseSpace::diagonal;
  bool input_covariances = true;  // also search a factor on each input's message covariance
  int folds = 5;                  // heldout_fixes
  double block_s = 1.0;           // heldout_fixes: fixes of one block are held out together [s]
  double outage_s = 60.0;         // outage: L [s]
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
};
FixScore score_of(std::span<const rlnode::ReplayOutput> outputs);
// `s` replayed over each schedule, its held-out fixes scored together.
FixScore replay_score(const rlnode::Recording& rec, std::span<const rlnode::Schedule> schedules,
                      const rlnode::ReplaySettings& s);

// The roles of the fixes under each protocol.
std::vector<std::vector<rlnode::FixRole>> heldout_fix_folds(const rlnode::Recording& rec, int folds,
                                                            double block_s, std::int64_t until_ns);
std::vector<rlnode::FixRole> outage_roles(const rlnode::Recording& rec, double outage_s, std::int64_t until_ns);

class RlObjective {
 public:
  // Lays out both parts' schedules and scores `base` on them. Throws
  // std::invalid_argument for invalid options, a recording without GPS fixes,
  // or a part the fitness uses that scores no fix before `until_ns`.
  RlObjective(const rlnode::Recording& rec, const rlnode::ReplaySettings& base, const RlTuneOptions& options);

  double fitness(std::span<const double> x) const;
  std::pair<std::vector<double>, std::vector<double>> bounds() const { return space_.box(); }

  const BoxSpace& space() const { return space_; }
  rlnode::ReplaySettings settings_at(std::span<const double> x) const;
  // Per part: the held-out fixes' and the outages' scores, whether or not the
  // fitness uses them; the base settings' own, from the constructor.
  FixScore heldout_score(const rlnode::ReplaySettings& s) const { return replay_score(*rec_, heldout_, s); }
  FixScore outage_score(const rlnode::ReplaySettings& s) const { return replay_score(*rec_, outage_, s); }
  const FixScore& baseline_heldout() const { return heldout_base_; }
  const FixScore& baseline_outage() const { return outage_base_; }
  double baseline_fitness() const { return combine(heldout_base_, outage_base_); }
  const RlTuneOptions& options() const { return options_; }
  // fitness() calls whose replay diverged (scored as a penalty), so far.
  long diverged() const { return diverged_->load(); }

 private:
  const rlnode::Recording* rec_;
  rlnode::ReplaySettings base_;
  RlTuneOptions options_;
  BoxSpace space_;
  std::vector<std::vector<int>> noise_members_;  // per noise parameter: the diagonal entries it scales
  std::vector<int> cov_sensors_;                 // per covariance parameter: the sensor
  std::vector<rlnode::Schedule> heldout_, outage_;
  FixScore heldout_base_, outage_base_;
  std::unique_ptr<std::atomic<long>> diverged_ = std::make_unique<std::atomic<long>>(0);
  // The fitness of the two parts' scores (kDiverged-like penalty when a used part is not finite).
  double combine(const FixScore& heldout, const FixScore& outage) const;
};

}  // namespace odotune
