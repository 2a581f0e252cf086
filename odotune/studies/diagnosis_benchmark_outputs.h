// The files of `odotune study diagnosis --out DIR` (docs/diagnosis/benchmark.md):
//   cases.csv      one row per case: seed, category, recordings (and held-out
//                  recordings), robot, drive, odometry, rates and
//                  noise, reference shape, true effects, detectability (gain
//                  and floor per effect), findings, verdict and why, timing;
//   confusion.csv  true (detectable) effect × named effect (Confusion in
//                  diagnosis_benchmark.h), with "none" and `unexplained`;
//   confusion.png  and .svg: the same as a heat map (gnuplot, odotune/results/gnuplot.h),
//                  each row coloured by its share of the row's cases;
//   summary.md     rates per category against the aims (docs/diagnosis/benchmark.md), failures by
//                  kind, per-effect recall and precision, parameter errors,
//                  time per case, breakdowns by reference shape and odometry,
//                  and the failed cases with why;
//   tracks/        (--keep-tracks) case_IIII.csv, each re-runnable with
//                  `odotune diagnose`; case_IIII_rK.csv (K from 1) for the
//                  recordings of a multi-recording case, the held-out ones
//                  last (`odotune diagnose r1 ... --heldout rN`).
// Every file is written atomically (odotune/core/atomic_file.h; figures through a
// temporary and a rename), the figure first, then the CSVs, then summary.md.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <odotune/studies/diagnosis_benchmark.h>
#include <odotune/studies/study_runs.h>

namespace odotune::studies {

std::string cases_csv(const DiagnosisBenchmark& b);
std::string confusion_csv(const Confusion& c);
// `command` is the command line that regenerates the run.
std::string benchmark_summary_markdown(const DiagnosisBenchmark& b, const std::string& command);

// Writes the files above (not the tracks) into `out` (which must exist);
// returns their paths in the order written. Throws std::runtime_error when a
// file cannot be written or gnuplot fails.
std::vector<std::filesystem::path> write_benchmark_outputs(
    const DiagnosisBenchmark& b, const std::filesystem::path& out, const std::string& command);

// What the command runs: checks the options, gnuplot and the --out folder
// (created when missing; OUT/tracks too with keep_tracks) before the long
// work, runs the benchmark with progress, hands the summary to hooks.tables,
// then writes the files. Throws core::Failure (one line) for bad options,
// a missing gnuplot, an unusable --out, an interrupted run or a case that
// cannot be simulated; std::runtime_error when a file cannot be written.
struct DiagnosisBenchmarkRequest {
  std::string out;
  bool keep_tracks = false;
  DiagnosisBenchmarkOptions options;  // tracks_dir is set from out and keep_tracks
  const std::atomic<bool>* stop = nullptr;
};
StudyRun run_diagnosis_benchmark_to_folder(const DiagnosisBenchmarkRequest& request,
                                           const StudyHooks& hooks = {});

// The command line of a request (defaults left out).
std::string benchmark_command_line(const DiagnosisBenchmarkRequest& request);

}  // namespace odotune::studies
