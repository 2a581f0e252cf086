// robot_localization's process noise searched in stages, so that the answer
// depends on the recording rather than on the seed (docs/husky.md, "How the
// tune searches"):
//   1. grid (deterministic): every block of the noise (position, orientation,
//      linear velocity, angular velocity, acceleration) scaled by one of
//      10^levels, each combination scored;
//   2. profile (deterministic): per parameter of the objective's space, the
//      range of factors over which the data fitness stays within `tolerance`
//      of its best, the others held. Parameters whose range holds the file's
//      value (factor 1) are reset to it: the recording did not determine them.
//      If resetting all of them changes the fitness by `tolerance` or more,
//      those that cost most are kept tuned until it does not.
//   3. refinement (seeded): the solver within ± refine_decades of that point,
//      over the parameters the profile found determined; then their profile
//      and reset again.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <odotune/jobs/tune_job.h>
#include <odotune/objectives/rl_objective.h>
#include <odotune/objectives/rl_search_options.h>
#include <odotune/tuner/summary.h>

namespace odotune::jobs {

// One tuned parameter's profile.
struct RlParamProfile {
  double lo = 0.0, hi = 0.0;   // factors: the range within tolerance of the best
  bool determined = true;      // false: the range holds 1 and the file's value was kept
  double at_file_value = 0.0;  // the data fitness with this parameter at factor 1, the others held
};

// The deterministic stages, shared by every start: the grid, then its best
// profiled and reset.
struct RlGridResult {
  std::vector<double> x;                 // box coordinates: the grid's best, after the reset
  double fitness = 0.0;                  // the fitness there (with the prior)
  std::vector<RlParamProfile> profiles;  // per parameter (empty without a profile)
  long points = 0;                       // the grid's combinations
  long evaluations = 0;                  // with the profile's
  double seconds = 0.0;
};
// The points rl_grid_stage evaluates before its profile (1 without a grid).
long rl_grid_points(const objectives::RlObjective& objective, const objectives::RlSearchOptions& options);
RlGridResult rl_grid_stage(const objectives::RlObjective& objective, const objectives::RlSearchOptions& options,
                           const SolverSettings& settings);

// The seeded stage for one start (its seed in `settings`): the refinement of
// the parameters the grid's profile found determined (all without a
// profile), then their profile and reset again. Without a refinement, or when
// it does not beat the grid, the start is the grid's result.
struct RlStartResult {
  std::uint64_t seed = 0;
  tuner::Summary refinement;             // the solver's run (best_x before the profile)
  std::vector<double> x;                 // box coordinates after the profile's reset
  double fitness = 0.0;                  // data fitness at x
  double refined_fitness = 0.0;          // data fitness at the refinement's best
  std::vector<RlParamProfile> profiles;  // per parameter (empty without a profile)
  long evaluations = 0;                  // refinement and profile
  double seconds = 0.0;
};
RlStartResult rl_refine_and_profile(const objectives::RlObjective& objective, const RlGridResult& grid,
                                    const objectives::RlSearchOptions& options, const SolverSettings& settings);

}  // namespace odotune::jobs
