// `odotune report`: everything a morning-after reader wants from a results
// store, written into one folder (the study's Figures 3–5 and Table 1, plus
// convergence and generalisation) and gathered in a self-contained
// index.html. Computation and file output only; the command prints.
//
// Files (every one written atomically; figures as STEM.png + STEM.svg):
//   heatmap_<model>_<metric>           improvement % per mode × track (Fig. 3)
//   heatmap_heldout_<model>_<metric>   the same for leave-one-track-out runs
//   boxplots[_heldout]                 improvement % per model and metric (Fig. 4)
//   table1.csv, table1.md              absolute RMSE per track × mode (Table 1)
//   generalisation.md                  per-track vs held-out improvement
//   trajectories_<track>               GT, baseline EKF, best tuned run per model (Fig. 5)
//   convergence_<track>                best fitness vs evaluations per model
//   index.html                         all of the above
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <odotune/objectives/fitness_mode.h>

namespace odotune::jobs {

struct ReportRequest {
  std::filesystem::path store;
  std::filesystem::path out_dir;
  // Track of the trajectory overlay (empty = every track of the experiment).
  std::string trajectory_track;
  // Fitness mode of the trajectory and convergence figures (the heatmaps show 1..7).
  objectives::FitnessMode mode = objectives::kDefaultFitnessMode;
  // Track files that take precedence over those the experiment names
  // (for a store whose experiment's tracks have moved).
  std::vector<std::string> track_files;
};

struct ReportOutcome {
  std::string experiment;
  long runs = 0, heldout_runs = 0;
  std::vector<std::filesystem::path> files;  // written, in order
  std::vector<std::string> notes;            // what was left out and why
  std::string headline;                      // one line: mean RMSE improvement per model
};

// Throws core::Failure (one line) on a missing or empty store, an
// unwritable folder, gnuplot failing or an unknown trajectory track.
ReportOutcome write_report(const ReportRequest& request);

}  // namespace odotune::jobs
