// odotune study resampling|calibration: the Monte-Carlo studies of Tables I
// and II of Fariña, Toledo & Acosta (RA-L 2026) on simulated wheelchair
// tracks. The computation is studies/calibration_study.h, the files
// studies/study_outputs.h; this command reads the flags and scenarios, shows
// progress and prints the table.
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include <fmt/format.h>

#include "studies/calibration_study.h"
#include "cli/commands.h"
#include "core/failure.h"
#include "studies/learned_study.h"
#include "studies/learned_study_outputs.h"
#include "cli/progress.h"
#include "formats/scenario_yaml.h"
#include "studies/study_outputs.h"
#include "studies/study_tables.h"
#include "results/gnuplot.h"

namespace odotune::cli {

namespace {
namespace fs = std::filesystem;

struct StudyArgs {
  std::string out, scenario, step_scenario;
  StudyOptions options;
};

std::string default_scenario(const char* file) {
  return (fs::path(ODOTUNE_SOURCE_DIR) / "scenarios" / file).string();
}

sim::Scenario read_scenario(const std::string& path) {
  try {
    return load_scenario(path);
  } catch (const ScenarioError& e) {
    throw Failure(e.what());
  }
}

// Checks the options, that the figures can be drawn and that the output
// folder exists or can be made, before the long computation.
void prepare(const StudyArgs& a) {
  std::string why;
  if (!a.options.IsValid(&why)) throw Failure("study: " + why);
  if (!results::gnuplot_available())
    throw Failure("study: gnuplot not found on PATH (needed for the figures); install it (apt-get install gnuplot)");
  const fs::path out(a.out);
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw Failure(fmt::format("{}: --out exists and is not a folder", a.out));
  fs::create_directories(out, ec);
  if (ec) throw Failure(fmt::format("{}: cannot create the output folder: {}", a.out, ec.message()));
}

// The command line that regenerates the outputs (defaults left out).
std::string command_line(const std::string& which, const StudyArgs& a, const StudyOptions& defaults) {
  std::string c = "odotune study " + which + " --out " + a.out;
  if (a.options.runs != defaults.runs) c += fmt::format(" --runs {}", a.options.runs);
  if (a.options.seed != defaults.seed) c += fmt::format(" --seed {}", a.options.seed);
  if (which == "resampling" && a.options.pf_particles != defaults.pf_particles)
    c += fmt::format(" --particles {}", a.options.pf_particles);
  if (which == "calibration" && a.options.adaptive_initial_particles != 0)
    c += fmt::format(" --particles {}", a.options.adaptive_initial_particles);
  if (a.scenario != default_scenario("wheelchair.yaml")) c += " --scenario " + a.scenario;
  if (which == "calibration" && a.step_scenario != default_scenario("wheelchair_step.yaml"))
    c += " --step-scenario " + a.step_scenario;
  return c;
}

// A path inside the source tree relative to it ("scenarios/wheelchair.yaml"),
// any other as given.
std::string display_path(const std::string& path) {
  std::error_code ec;
  const fs::path source = fs::weakly_canonical(ODOTUNE_SOURCE_DIR, ec);
  const fs::path p = fs::weakly_canonical(path, ec);
  if (ec) return path;
  const fs::path rel = p.lexically_relative(source);
  return !rel.empty() && *rel.begin() != ".." ? rel.string() : path;
}

StudyContext context(const std::string& which, const StudyArgs& a, const StudyOptions& defaults) {
  StudyContext c;
  c.command = command_line(which, a, defaults);
  c.scenario_file = display_path(a.scenario);
  c.step_scenario_file = display_path(a.step_scenario);
  c.hardware_threads = std::thread::hardware_concurrency();
  return c;
}

void print_files(const std::vector<fs::path>& files, const std::string& dir, double wall_s) {
  std::string names;
  for (const auto& f : files) names += (names.empty() ? "" : ", ") + f.filename().string();
  fmt::print("\nwrote {} files to {} ({}); the study took {:.1f} s\n", files.size(), dir, names, wall_s);
}

// Adds the options both studies share.
CLI::App* add_study(CLI::App* study, const std::string& name, const std::string& help, StudyArgs* a) {
  auto* sub = study->add_subcommand(name, help);
  sub->add_option("--out", a->out, "folder for the tables (Markdown, CSV) and figures (PNG, SVG)")->required();
  sub->add_option("--runs", a->options.runs, "Monte-Carlo runs (run r: seed + r)")->default_val(a->options.runs);
  sub->add_option("--seed", a->options.seed, "base seed")->default_val(a->options.seed);
  sub->add_option("--threads", a->options.threads,
                  "OpenMP threads over runs × cells (0 = all cores); results do not depend on it, "
                  "except timing")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--scenario", a->scenario, "scenario of the track (constant conditions)")
      ->default_val(default_scenario("wheelchair.yaml"));
  return sub;
}

template <class Run>
auto run_with_progress(const std::string& label, const Run& run) {
  Progress progress(label, "tasks");
  auto out = run([&progress](long done, long total) { progress.update(done, total); });
  progress.finish();
  return out;
}

// ---------------------------------------------------------------- study learned

struct LearnedArgs {
  std::string out;
  // kLearnedScenarioRoles order.
  std::string scenarios[5];
  LearnedStudyOptions options;
};

const char* const kLearnedScenarioFiles[5] = {"wheelchair_learn.yaml", "wheelchair_learn_eval.yaml",
                                              "wheelchair_learn_step.yaml", "wheelchair_slip.yaml",
                                              "wheelchair_slip_eval.yaml"};
const char* const kLearnedScenarioFlags[5] = {"--learn-scenario", "--eval-scenario", "--step-scenario",
                                              "--slip-scenario", "--slip-eval-scenario"};

std::string learned_command(const LearnedArgs& a) {
  const LearnedStudyOptions d;
  std::string c = "odotune study learned --out " + a.out;
  if (a.options.seed != d.seed) c += fmt::format(" --seed {}", a.options.seed);
  if (a.options.iterations != d.iterations) c += fmt::format(" --iterations {}", a.options.iterations);
  if (a.options.retrain_iterations != d.retrain_iterations)
    c += fmt::format(" --retrain-iterations {}", a.options.retrain_iterations);
  if (a.options.samples_per_retrain != d.samples_per_retrain)
    c += fmt::format(" --every {}", a.options.samples_per_retrain);
  if (a.options.slip_drives != d.slip_drives) c += fmt::format(" --slip-drives {}", a.options.slip_drives);
  if (a.options.slip_stride != d.slip_stride) c += fmt::format(" --slip-stride {}", a.options.slip_stride);
  for (int i = 0; i < 5; ++i)
    if (a.scenarios[i] != default_scenario(kLearnedScenarioFiles[i]))
      c += std::string(" ") + kLearnedScenarioFlags[i] + " " + a.scenarios[i];
  return c;
}

void register_learned_study(CLI::App* study) {
  auto a = std::make_shared<LearnedArgs>();
  auto* sub = study->add_subcommand(
      "learned",
      "Tables 1-3 of Fariña et al. (Sensors 2023): LSTM vs traditional odometry, online retraining after a "
      "radius change, UKF with variable vs static odometry covariance under slip");
  sub->add_option("--out", a->out, "folder for the tables (Markdown, CSV), results.json, model.json and figures")
      ->required();
  sub->add_option("--seed", a->options.seed, "base seed (scenario i: seed + i; initial weights)")
      ->default_val(a->options.seed);
  sub->add_option("--iterations", a->options.iterations, "Ceres iterations of each initial training")
      ->default_val(a->options.iterations);
  sub->add_option("--retrain-iterations", a->options.retrain_iterations, "Ceres iterations of each online retrain")
      ->default_val(a->options.retrain_iterations);
  sub->add_option("--every", a->options.samples_per_retrain, "retrain every N well-localised samples (paper: 300)")
      ->default_val(a->options.samples_per_retrain);
  sub->add_option("--slip-drives", a->options.slip_drives,
                  "drives the slip detector trains on: the slip scenario and N-1 more of its route with random "
                  "slip episodes")
      ->default_val(a->options.slip_drives);
  sub->add_option("--slip-stride", a->options.slip_stride, "train the slip detector on every N-th window")
      ->default_val(a->options.slip_stride);
  sub->add_option("--threads", a->options.threads, "threads evaluating the training windows (results do not depend "
                                                   "on it)")
      ->check(CLI::PositiveNumber);
  const char* const helps[5] = {"scenario the velocity nets are trained on",
                                "held-out scenario of Table 1",
                                "scenario with a radius change (radius_step) of Table 2",
                                "scenario with slip episodes the detector is trained on",
                                "held-out scenario with slip episodes of Table 3"};
  for (int i = 0; i < 5; ++i)
    sub->add_option(kLearnedScenarioFlags[i], a->scenarios[i], helps[i])
        ->default_val(default_scenario(kLearnedScenarioFiles[i]));
  sub->callback([a] {
    LearnedStudyScenarios sc{read_scenario(a->scenarios[0]), read_scenario(a->scenarios[1]),
                             read_scenario(a->scenarios[2]), read_scenario(a->scenarios[3]),
                             read_scenario(a->scenarios[4])};
    std::string why;
    if (!a->options.IsValid(&why)) throw Failure("study learned: " + why);
    try {
      check_learned_scenarios(sc);
    } catch (const std::invalid_argument& e) {
      throw Failure("study learned: " + std::string(e.what()));
    }
    if (!results::gnuplot_available())
      throw Failure("study: gnuplot not found on PATH (needed for the figures); install it (apt-get install gnuplot)");
    const fs::path out(a->out);
    std::error_code ec;
    if (fs::exists(out, ec) && !fs::is_directory(out, ec))
      throw Failure(fmt::format("{}: --out exists and is not a folder", a->out));
    fs::create_directories(out, ec);
    if (ec) throw Failure(fmt::format("{}: cannot create the output folder: {}", a->out, ec.message()));

    LearnedStudy s;
    {
      Progress progress("study learned", "stages");
      try {
        s = run_learned_study(sc, a->options, [&progress](long done, long total, const std::string& stage) {
          progress.set_label("study learned: " + stage);
          progress.update(done, total);
        });
      } catch (const std::invalid_argument& e) {
        throw Failure(e.what());
      }
      progress.finish();
    }
    LearnedStudyContext c;
    c.command = learned_command(*a);
    for (const auto& f : a->scenarios) c.scenario_files.push_back(display_path(f));
    fmt::print("Table 1 ({}):\n{}\n", s.table1.track, results::to_markdown(learned_table1_text(s)));
    fmt::print("Table 2 ({}), after the radius change at {:g} s:\n{}\n", s.table2.track, s.table2.change_t_s,
               results::to_markdown(learned_table2_text(s, true)));
    fmt::print("{}\n", results::to_markdown(learned_table2_cost_text(s)));
    fmt::print("Table 3 ({}):\n{}", s.table3.track, results::to_markdown(learned_table3_text(s)));
    std::vector<fs::path> files;
    try {
      files = write_learned_outputs(s, c, out);
    } catch (const std::exception& e) {
      throw Failure(fmt::format("{}: {}", a->out, e.what()));
    }
    print_files(files, a->out, s.wall_s);
  });
}

}  // namespace

void register_study(CLI::App& app) {
  auto* study = app.add_subcommand(
      "study", "Monte-Carlo studies of online odometry calibration (Tables I and II of Fariña et al.)");
  study->require_subcommand(1);
  study->footer(
      "Example:\n"
      "  odotune study resampling --out docs/calibration/resampling\n"
      "  odotune study calibration --out docs/calibration/calibration --runs 40 --seed 7\n"
      "  odotune study learned --out docs/learned\n"
      "Each run simulates the wheelchair scenario with its own seed and random true radii.");

  auto resampling = std::make_shared<StudyArgs>();
  auto* rs = add_study(study, "resampling",
                       "Table I: 4 resamplers × 3 resampling policies of the plain PF (final radius "
                       "errors, V/W RMSE, ms per iteration)",
                       resampling.get());
  rs->add_option("--particles", resampling->options.pf_particles, "N of the plain PF (the paper's 5000)")
      ->default_val(resampling->options.pf_particles);
  rs->callback([resampling] {
    const StudyArgs& a = *resampling;
    const sim::Scenario scenario = read_scenario(a.scenario);
    prepare(a);
    ResamplingStudy s;
    try {
      s = run_with_progress("study resampling", [&](const StudyProgress& p) {
        return run_resampling_study(scenario, a.options, p);
      });
    } catch (const std::invalid_argument& e) {
      throw Failure(e.what());
    }
    const StudyContext c = context("resampling", a, StudyOptions{});
    fmt::print("{}", results::to_markdown(table1_text(s)));
    print_files(write_resampling_outputs(s, c, a.out), a.out, s.wall_s);
  });

  auto calibration = std::make_shared<StudyArgs>();
  auto* cs = add_study(study, "calibration",
                       "Table II: adaptive PF vs DKF vs batch vs none, constant and changing "
                       "conditions (radius errors, pose RMSE, convergence)",
                       calibration.get());
  cs->add_option("--step-scenario", calibration->step_scenario,
                 "scenario of the changing-conditions track (radius_step)")
      ->default_val(default_scenario("wheelchair_step.yaml"));
  cs->add_option("--particles", calibration->options.adaptive_initial_particles,
                 "initial N of the adaptive PF (0 = the paper's 8000)")
      ->check(CLI::NonNegativeNumber);
  cs->callback([calibration] {
    const StudyArgs& a = *calibration;
    const sim::Scenario constant = read_scenario(a.scenario);
    const sim::Scenario step = read_scenario(a.step_scenario);
    prepare(a);
    CalibrationStudy s;
    try {
      s = run_with_progress("study calibration", [&](const StudyProgress& p) {
        return run_calibration_study(constant, step, a.options, p);
      });
    } catch (const std::invalid_argument& e) {
      throw Failure(e.what());
    }
    const StudyContext c = context("calibration", a, StudyOptions{});
    fmt::print("{}", results::to_markdown(table2_text(s)));
    print_files(write_calibration_outputs(s, c, a.out), a.out, s.wall_s);
  });

  register_learned_study(study);
}

}  // namespace odotune::cli
