// One finished tuning run of an experiment grid: the row the results store
// keeps and the report and export read. Plain data, SI units (metres).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace odotune::results {

struct Metrics {
  double rmse_m = 0.0, mae_m = 0.0, maxe_m = 0.0;
};

struct ConvergencePoint {
  long evaluations = 0;
  double best_fitness = 0.0;
};

// How well the tuning data pin one tuned parameter: the range [lo, hi]
// (physical units, as `params`) over which the tuning fitness stays within
// 2 % of its best, and whether the recording determined it (false: its range
// holds the file's own value, which the run then kept).
struct ParamRange {
  double lo = 0.0, hi = 0.0;
  bool determined = true;
};

// A stored run is data: its model and solver are kept as their names and its
// fitness mode as its number, as the store's columns hold them; a command that
// reads them back parses them there (odotune/jobs/store_access.h, run_model).
struct RunRecord {
  // The cell: model × track × mode × seed (× held-out track for leave-one-out).
  std::string model;          // objectives::to_string(TunedModel): "rq", "alpha", …, "rl-ekf"
  std::string track;          // track name (tuned on; "all-but-X" for leave-one-out)
  std::string heldout_track;  // empty unless leave-one-track-out
  int mode = 7;  // fitness mode 1..9 (8, 9: scored on held-out fixes); rl-ekf/rl-ukf: objectives::stored_mode
  std::uint64_t seed = 0;
  std::string solver = "pso";  // tuner::SolverChoice::name()
  // The result.
  std::vector<std::string> param_names;
  std::vector<double> params;  // physical values (units as in ParamSpace)
  // Per parameter (param_names' order), for runs whose tune profiles its
  // parameters (model rl-ekf); empty otherwise.
  std::vector<ParamRange> param_ranges;
  double best_fitness = 0.0;
  Metrics baseline, tuned;  // on `track` (or on the held-out track)
  long evaluations = 0;
  double seconds = 0.0;
  long diverged = 0;  // evaluations that diverged
  std::string termination;
  std::vector<ConvergencePoint> convergence;

  // A leave-one-track-out run (tuned on the other tracks, scored on heldout_track).
  bool is_heldout() const { return !heldout_track.empty(); }
  // The track the run's scores are for: its own track, or the held-out one.
  const std::string& scored_track() const { return is_heldout() ? heldout_track : track; }

  // Improvement of tuned over baseline in % (positive = better).
  double improvement_rmse_pct() const { return pct(baseline.rmse_m, tuned.rmse_m); }
  double improvement_mae_pct() const { return pct(baseline.mae_m, tuned.mae_m); }
  double improvement_maxe_pct() const { return pct(baseline.maxe_m, tuned.maxe_m); }

 private:
  static double pct(double b, double t) { return b > 0.0 ? 100.0 * (b - t) / b : 0.0; }
};

}  // namespace odotune::results
