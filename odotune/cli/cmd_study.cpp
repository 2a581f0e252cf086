// odotune study resampling|calibration|learned|diagnosis: the Monte-Carlo
// studies of Tables I and II of Fariña, Toledo & Acosta (RA-L 2026) and
// Tables 1-3 of Fariña et al. (Sensors 2023) on simulated wheelchair tracks,
// and the random benchmark of the diagnosis (docs/diagnosis/benchmark.md).
// The work is odotune/studies/study_runs.h and odotune/studies/diagnosis_benchmark_outputs.h;
// this command reads the flags, shows progress and prints the tables and the
// files written.
#include <memory>
#include <string>

#include <fmt/format.h>

#include <odotune/cli/commands.h>
#include <odotune/cli/output.h>
#include <odotune/cli/progress.h>
#include <odotune/studies/diagnosis_benchmark_outputs.h>
#include <odotune/studies/study_runs.h>

namespace odotune::cli {

namespace {

// SOURCE_DIR/scenarios/FILE of this build.
std::string source_scenario(const char* file) { return studies::default_scenario(ODOTUNE_SOURCE_DIR, file); }

// Runs one study with progress on stderr, then prints its tables and files.
template <class Request, class Run>
void run_and_print(const std::string& label, const std::string& unit, Request request, Run run) {
  if constexpr (requires { request.source_dir; }) request.source_dir = ODOTUNE_SOURCE_DIR;
  Progress progress(label, unit);
  studies::StudyHooks hooks;
  hooks.progress = [&](long done, long total, const std::string& stage) {
    if (!stage.empty()) progress.set_label(label + ": " + stage);
    progress.update(done, total);
  };
  hooks.tables = [&](const std::string& tables) {
    progress.finish();
    fmt::print("{}", tables);
  };
  const studies::StudyRun r = run(request, hooks);
  std::string names;
  for (const auto& f : r.files) names += (names.empty() ? "" : ", ") + f.filename().string();
  fmt::print("\nwrote {} files to {} ({}); the study took {:.1f} s\n", r.files.size(), request.out, names,
             r.wall_s);
}

// Adds the options resampling and calibration share.
CLI::App* add_study(CLI::App* study, const std::string& name, const std::string& help,
                    studies::StudyRequest* r) {
  auto* sub = study->add_subcommand(name, help);
  sub->add_option("--out", r->out, "folder for the tables (Markdown, CSV) and figures (PNG, SVG)")->required();
  sub->add_option("--runs", r->options.runs, "Monte-Carlo runs (run r: seed + r)")
      ->default_val(r->options.runs);
  sub->add_option("--seed", r->options.seed, "base seed")->default_val(r->options.seed);
  sub->add_option("--threads", r->options.threads,
                  "OpenMP threads over runs × cells (0 = all cores); results do not depend on it, "
                  "except timing")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--scenario", r->scenario, "scenario of the track (constant conditions)")
      ->default_val(source_scenario(studies::kStudyScenarioFile));
  return sub;
}

void register_learned_study(CLI::App* study) {
  auto r = std::make_shared<studies::LearnedStudyRequest>();
  studies::LearnedStudyOptions& o = r->options;
  auto* sub = study->add_subcommand(
      "learned",
      "Tables 1-3 of Fariña et al. (Sensors 2023): LSTM vs traditional odometry, online retraining after a "
      "radius change, UKF with variable vs static odometry covariance under slip");
  sub->add_option("--out", r->out,
                  "folder for the tables (Markdown, CSV), results.json, model.json and figures")
      ->required();
  sub->add_option("--seed", o.seed, "base seed (scenario i: seed + i; initial weights)")->default_val(o.seed);
  sub->add_option("--iterations", o.iterations, "Ceres iterations of each initial training")
      ->default_val(o.iterations);
  sub->add_option("--retrain-iterations", o.retrain_iterations, "Ceres iterations of each online retrain")
      ->default_val(o.retrain_iterations);
  sub->add_option("--every", o.samples_per_retrain, "retrain every N well-localised samples (paper: 300)")
      ->default_val(o.samples_per_retrain);
  sub->add_option("--slip-drives", o.slip_drives,
                  "drives the slip detector trains on: the slip scenario and N-1 more of its route with random "
                  "slip episodes")
      ->default_val(o.slip_drives);
  sub->add_option("--slip-stride", o.slip_stride, "train the slip detector on every N-th window")
      ->default_val(o.slip_stride);
  sub->add_option("--threads", o.threads,
                  "threads evaluating the training windows (results do not depend "
                  "on it)")
      ->check(CLI::PositiveNumber);
  const char* const helps[5] = {"scenario the velocity nets are trained on", "held-out scenario of Table 1",
                                "scenario with a radius change (radius_step) of Table 2",
                                "scenario with slip episodes the detector is trained on",
                                "held-out scenario with slip episodes of Table 3"};
  for (int i = 0; i < 5; ++i)
    sub->add_option(studies::kLearnedScenarioFlags[i], r->scenarios[i], helps[i])
        ->default_val(source_scenario(studies::kLearnedScenarioFiles[i]));
  sub->callback([r] { run_and_print("study learned", "stages", *r, studies::run_learned_to_folder); });
}

void register_diagnosis_study(CLI::App* study) {
  auto r = std::make_shared<studies::DiagnosisBenchmarkRequest>();
  studies::DiagnosisBenchmarkOptions& o = r->options;
  auto* sub = study->add_subcommand(
      "diagnosis",
      "random benchmark of `odotune diagnose`: random robots, drives, odometry, references and 0-2 effects; "
      "graded against the truth (confusion matrix, recall, precision, parameter errors, time per case)");
  sub->add_option("--out", r->out, "folder for summary.md, cases.csv, confusion.csv and confusion.png/.svg")
      ->required();
  sub->add_option("--cases", o.cases, "number of random cases")
      ->default_val(o.cases)
      ->check(CLI::Range(1, 100000));
  sub->add_option("--seed", o.seed, "seed of the run (case i draws from a hash of seed and i)")
      ->default_val(o.seed);
  sub->add_option("--first", o.first, "index of the first case (re-run case I alone: --first I --cases 1)")
      ->default_val(o.first)
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--min-minutes", o.draw.min_minutes, "shortest drive [min]")->capture_default_str();
  sub->add_option("--max-minutes", o.draw.max_minutes, "longest drive [min]")->capture_default_str();
  sub->add_option("--max-rate", o.draw.max_rate_hz, "highest odometry, gyro and ground-truth rate drawn [Hz]")
      ->capture_default_str();
  sub->add_option("--null-share", o.draw.null_share, "share of cases with no effect")->capture_default_str();
  sub->add_option("--two-share", o.draw.two_share, "share of cases with two effects (the rest have one)")
      ->capture_default_str();
  sub->add_option("--multi-share", o.draw.multi_share,
                  "share of multi-recording cases (2-4 recordings of one robot, the last held out)")
      ->capture_default_str();
  sub->add_flag("--keep-tracks", r->keep_tracks,
                "also write each case's track to OUT/tracks/case_IIII.csv (case_IIII_rK.csv per recording)");
  add_threads_option(sub, &o.threads);
  sub->footer("Example:\n  odotune study diagnosis --cases 20 --seed 1001 --max-minutes 3 --out /tmp/bench\n"
              "Development runs use seeds other than the committed docs run (docs/diagnosis/benchmark.md).");
  sub->callback([r] {
    apply_threads(r->options.threads);
    InterruptGuard guard;
    r->stop = guard.flag();
    run_and_print("study diagnosis", "cases", *r, studies::run_diagnosis_benchmark_to_folder);
  });
}

}  // namespace

void register_study(CLI::App& app) {
  auto* study = app.add_subcommand(
      "study", "Monte-Carlo studies of online odometry calibration (Tables I and II of Fariña et al.)");
  study->require_subcommand(1);
  study->footer("Example:\n"
                "  odotune study resampling --out docs/calibration/resampling\n"
                "  odotune study calibration --out docs/calibration/calibration --runs 40 --seed 7\n"
                "  odotune study learned --out docs/learned\n"
                "Each run simulates the wheelchair scenario with its own seed and random true radii.");

  auto resampling = std::make_shared<studies::StudyRequest>();
  auto* rs = add_study(study, "resampling",
                       "Table I: 4 resamplers × 3 resampling policies of the plain PF (final radius "
                       "errors, V/W RMSE, ms per iteration)",
                       resampling.get());
  rs->add_option("--particles", resampling->options.pf_particles, "N of the plain PF (the paper's 5000)")
      ->default_val(resampling->options.pf_particles);
  rs->callback([resampling] {
    run_and_print("study resampling", "tasks", *resampling, studies::run_resampling_to_folder);
  });

  auto calibration = std::make_shared<studies::StudyRequest>();
  auto* cs = add_study(study, "calibration",
                       "Table II: adaptive PF vs DKF vs batch vs none, constant and changing "
                       "conditions (radius errors, pose RMSE, convergence)",
                       calibration.get());
  cs->add_option("--step-scenario", calibration->step_scenario,
                 "scenario of the changing-conditions track (radius_step)")
      ->default_val(source_scenario(studies::kStudyStepScenarioFile));
  cs->add_option("--particles", calibration->options.adaptive_initial_particles,
                 "initial N of the adaptive PF (0 = the paper's 8000)")
      ->check(CLI::NonNegativeNumber);
  cs->callback([calibration] {
    run_and_print("study calibration", "tasks", *calibration, studies::run_calibration_to_folder);
  });

  register_learned_study(study);
  register_diagnosis_study(study);
}

}  // namespace odotune::cli
