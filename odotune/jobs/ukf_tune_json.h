// The --json document of `tune --model ukf` (odotune/cli/tune_output.h prints it).
//
// --json keys (as the EKF tune JSON; lengths in metres):
//   model             "ukf"
//   mode, mode_name, solver, seed   as the EKF tune JSON; particles, iterations for pso
//   fusion_rate_hz    the fusion rate (10 Hz, the paper's)
//   params            tuned values, name → value (ukf_space() names)
//   param_units       name → unit
//   default_params    the defaults (the baseline), name → value
//   default_kept      true when the defaults scored better than the solver's best
//   baseline, tuned   mean over tracks of the fused pose's position errors
//                     {rmse_m, mae_m, maxe_m, samples}
//   improvement_pct   {rmse, mae, maxe}: 100·(baseline − tuned)/baseline
//   baseline_fitness, tuned_fitness   the objective's (mode's) value
//   evaluations, seconds, termination   the solver's
//   failures          evaluations that scored the divergence penalty
//   tracks            per track: {track, baseline, tuned}
//   convergence       [{iteration, evaluations, best_fitness}] of the solver
#pragma once

#include <nlohmann/json.hpp>

#include <odotune/jobs/ukf_tune_job.h>

namespace odotune::jobs {

nlohmann::json ukf_tune_json(const UkfTuneOutcome& o, double fusion_rate_hz);

}  // namespace odotune::jobs
