// What `odotune study resampling|calibration` writes into its --out folder:
// the tables (study_tables.h) and the figures, built here from the plain
// study results. Every file is written atomically (odotune/core/atomic_file.h;
// figures: odotune/results/gnuplot.h, PNG + SVG both or neither).
//
//   resampling:  table1.md, table1.csv, table1_runs.csv,
//                fig3_4_resampling.{png,svg}
//   calibration: table2.md, table2.csv, table2_runs.csv,
//                fig5_particles, fig6a_radii_constant, fig6b_radii_step,
//                fig8_dkf_vs_pf_step, fig8_dkf_vs_pf_constant (.png + .svg);
//                the many-run figures (5, 6a, 6b) show at most the first 10 runs
#pragma once

#include <filesystem>
#include <vector>

#include <odotune/results/study_figures.h>
#include <odotune/studies/calibration_study.h>
#include <odotune/studies/study_tables.h>

namespace odotune::studies {

// The Figure 3/4 analogue's data: groups = resamplers, series = policies
// (the study's order). Panel 0: radius error per run, (|err R_R| + |err R_L|)/2,
// mean ± sd over runs; panel 1: ms per iteration. Each panel is normalised
// by its largest mean (so that the largest bar is 1, as the paper's Figure 3),
// the sds by the same factor.
struct ResamplingBars {
  std::vector<std::string> groups, series;
  std::vector<results::BarPanel> panels;
};
ResamplingBars resampling_bars(const ResamplingStudy& s);

// Writes the files listed above into `dir` (which must exist); returns them
// in order of writing. Throws std::runtime_error when a file or figure
// cannot be written.
std::vector<std::filesystem::path> write_resampling_outputs(const ResamplingStudy& s, const StudyContext& c,
                                                            const std::filesystem::path& dir);
std::vector<std::filesystem::path> write_calibration_outputs(const CalibrationStudy& s, const StudyContext& c,
                                                             const std::filesystem::path& dir);

}  // namespace odotune::studies
