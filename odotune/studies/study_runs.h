// What `odotune study resampling|calibration|learned` does besides reading
// its flags: the default scenario files, reading and checking the scenarios,
// checking for gnuplot and preparing the --out folder before the long work,
// the command line and setup text the outputs record, running the study
// (calibration_study.h, learned_study.h) and writing its files
// (study_outputs.h, learned_study_outputs.h). The command shows progress and
// prints the tables and the list of files.
//
// Errors. Before the long computation, core::Failure (one line) on a
// missing or invalid scenario file, invalid options, gnuplot missing, an
// --out that is not or cannot be made a folder, or a scenario the study
// cannot use (checked after the folder is created for resampling and
// calibration, before it for learned). After it, on a file that cannot be
// written: std::runtime_error from study_outputs.h (resampling, calibration),
// core::Failure "OUT: reason" (learned).
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <odotune/studies/calibration_study.h>
#include <odotune/studies/learned_study.h>

namespace odotune::studies {

// The default scenarios, files under SOURCE_DIR/scenarios/.
inline constexpr const char* kStudyScenarioFile = "wheelchair.yaml";           // resampling, calibration
inline constexpr const char* kStudyStepScenarioFile = "wheelchair_step.yaml";  // calibration
// The learned study's, and the flags that name them, in kLearnedScenarioRoles order.
inline constexpr const char* kLearnedScenarioFiles[5] = {"wheelchair_learn.yaml", "wheelchair_learn_eval.yaml",
                                                         "wheelchair_learn_step.yaml", "wheelchair_slip.yaml",
                                                         "wheelchair_slip_eval.yaml"};
inline constexpr const char* kLearnedScenarioFlags[5] = {
    "--learn-scenario", "--eval-scenario", "--step-scenario", "--slip-scenario", "--slip-eval-scenario"};

// SOURCE_DIR/scenarios/FILE.
std::string default_scenario(const std::string& source_dir, const std::string& file);

// `study resampling` (Table I) and `study calibration` (Table II).
struct StudyRequest {
  // The source tree: where the default scenarios are, and what the recorded
  // scenario paths are shown relative to. (The command passes its build's
  // ODOTUNE_SOURCE_DIR.)
  std::string source_dir;
  std::string out;            // the --out folder, created when missing
  std::string scenario;       // the track of constant conditions
  std::string step_scenario;  // the track of changing conditions (calibration only)
  StudyOptions options;
};

// `study learned` (Tables 1-3 of the Sensors 2023 paper).
struct LearnedStudyRequest {
  std::string source_dir;  // as StudyRequest::source_dir
  std::string out;
  std::string scenarios[5];  // kLearnedScenarioRoles order
  LearnedStudyOptions options;
};

struct StudyHooks {
  // Progress: (done, total, stage). The stage is "" for resampling and
  // calibration (tasks), the stage's name for learned (stages).
  std::function<void(long done, long total, const std::string& stage)> progress;
  // The tables as Markdown text, once computed and before the files are
  // written (so that a failure to write still leaves them shown).
  std::function<void(const std::string& tables)> tables;
};

struct StudyRun {
  std::vector<std::filesystem::path> files;  // written, in order
  double wall_s = 0.0;                       // the study's computation [s]
};

StudyRun run_resampling_to_folder(const StudyRequest& request, const StudyHooks& hooks = {});
StudyRun run_calibration_to_folder(const StudyRequest& request, const StudyHooks& hooks = {});
StudyRun run_learned_to_folder(const LearnedStudyRequest& request, const StudyHooks& hooks = {});

}  // namespace odotune::studies
