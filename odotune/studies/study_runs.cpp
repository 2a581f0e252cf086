#include <odotune/studies/study_runs.h>

#include <stdexcept>
#include <string_view>
#include <thread>

#include <fmt/format.h>

#include <odotune/core/failure.h>
#include <odotune/formats/scenario_yaml.h>
#include <odotune/results/gnuplot.h>
#include <odotune/studies/learned_study_outputs.h>
#include <odotune/studies/study_outputs.h>
#include <odotune/studies/study_tables.h>

namespace odotune::studies {

namespace {
namespace fs = std::filesystem;

// The two Monte-Carlo studies that share StudyRequest.
enum class Study { resampling, calibration };
std::string_view to_string(Study s) { return s == Study::resampling ? "resampling" : "calibration"; }

sim::Scenario read_scenario(const std::string& path) {
  try {
    return formats::load_scenario(path);
  } catch (const formats::ScenarioError& e) {
    throw core::Failure(e.what());
  }
}

// That the figures can be drawn and that the output folder exists or can be
// made, before the long computation.
void prepare_output(const std::string& out_dir) {
  if (!results::gnuplot_available())
    throw core::Failure(
        "study: gnuplot not found on PATH (needed for the figures); install it (apt-get install gnuplot)");
  const fs::path out(out_dir);
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw core::Failure(fmt::format("{}: --out exists and is not a folder", out_dir));
  fs::create_directories(out, ec);
  if (ec) throw core::Failure(fmt::format("{}: cannot create the output folder: {}", out_dir, ec.message()));
}

void prepare(const StudyRequest& r) {
  std::string why;
  if (!r.options.IsValid(&why)) throw core::Failure("study: " + why);
  prepare_output(r.out);
}

// The command line that regenerates the outputs (defaults left out).
std::string command_line(Study which, const StudyRequest& r) {
  const StudyOptions defaults;
  std::string c = fmt::format("odotune study {} --out {}", to_string(which), r.out);
  if (r.options.runs != defaults.runs) c += fmt::format(" --runs {}", r.options.runs);
  if (r.options.seed != defaults.seed) c += fmt::format(" --seed {}", r.options.seed);
  if (which == Study::resampling && r.options.pf_particles != defaults.pf_particles)
    c += fmt::format(" --particles {}", r.options.pf_particles);
  if (which == Study::calibration && r.options.adaptive_initial_particles != 0)
    c += fmt::format(" --particles {}", r.options.adaptive_initial_particles);
  if (r.scenario != default_scenario(r.source_dir, kStudyScenarioFile)) c += " --scenario " + r.scenario;
  if (which == Study::calibration && r.step_scenario != default_scenario(r.source_dir, kStudyStepScenarioFile))
    c += " --step-scenario " + r.step_scenario;
  return c;
}

std::string learned_command(const LearnedStudyRequest& r) {
  const LearnedStudyOptions d;
  const LearnedStudyOptions& o = r.options;
  std::string c = "odotune study learned --out " + r.out;
  if (o.seed != d.seed) c += fmt::format(" --seed {}", o.seed);
  if (o.iterations != d.iterations) c += fmt::format(" --iterations {}", o.iterations);
  if (o.retrain_iterations != d.retrain_iterations)
    c += fmt::format(" --retrain-iterations {}", o.retrain_iterations);
  if (o.samples_per_retrain != d.samples_per_retrain) c += fmt::format(" --every {}", o.samples_per_retrain);
  if (o.slip_drives != d.slip_drives) c += fmt::format(" --slip-drives {}", o.slip_drives);
  if (o.slip_stride != d.slip_stride) c += fmt::format(" --slip-stride {}", o.slip_stride);
  for (int i = 0; i < 5; ++i)
    if (r.scenarios[i] != default_scenario(r.source_dir, kLearnedScenarioFiles[i]))
      c += std::string(" ") + kLearnedScenarioFlags[i] + " " + r.scenarios[i];
  return c;
}

// A path inside the source tree relative to it ("scenarios/wheelchair.yaml"),
// any other as given.
std::string display_path(const std::string& source_dir, const std::string& path) {
  std::error_code ec;
  const fs::path source = fs::weakly_canonical(source_dir, ec);
  const fs::path p = fs::weakly_canonical(path, ec);
  if (ec) return path;
  const fs::path rel = p.lexically_relative(source);
  return !rel.empty() && *rel.begin() != ".." ? rel.string() : path;
}

StudyContext context(Study which, const StudyRequest& r) {
  StudyContext c;
  c.command = command_line(which, r);
  c.scenario_file = display_path(r.source_dir, r.scenario);
  c.step_scenario_file = display_path(r.source_dir, r.step_scenario);
  c.hardware_threads = std::thread::hardware_concurrency();
  return c;
}

// The study's progress callback from the hooks' (stage "").
StudyProgress task_progress(const StudyHooks& hooks) {
  if (!hooks.progress) return {};
  return [&hooks](long done, long total) { hooks.progress(done, total, ""); };
}

void show_tables(const StudyHooks& hooks, const std::string& tables) {
  if (hooks.tables) hooks.tables(tables);
}

}  // namespace

std::string default_scenario(const std::string& source_dir, const std::string& file) {
  return (fs::path(source_dir) / "scenarios" / file).string();
}

StudyRun run_resampling_to_folder(const StudyRequest& r, const StudyHooks& hooks) {
  const sim::Scenario scenario = read_scenario(r.scenario);
  prepare(r);
  ResamplingStudy s;
  try {
    s = run_resampling_study(scenario, r.options, task_progress(hooks));
  } catch (const std::invalid_argument& e) {
    throw core::Failure(e.what());
  }
  show_tables(hooks, results::to_markdown(table1_text(s)));
  return {write_resampling_outputs(s, context(Study::resampling, r), r.out), s.wall_s};
}

StudyRun run_calibration_to_folder(const StudyRequest& r, const StudyHooks& hooks) {
  const sim::Scenario constant = read_scenario(r.scenario);
  const sim::Scenario step = read_scenario(r.step_scenario);
  prepare(r);
  CalibrationStudy s;
  try {
    s = run_calibration_study(constant, step, r.options, task_progress(hooks));
  } catch (const std::invalid_argument& e) {
    throw core::Failure(e.what());
  }
  show_tables(hooks, results::to_markdown(table2_text(s)));
  return {write_calibration_outputs(s, context(Study::calibration, r), r.out), s.wall_s};
}

StudyRun run_learned_to_folder(const LearnedStudyRequest& r, const StudyHooks& hooks) {
  const LearnedStudyScenarios sc{read_scenario(r.scenarios[0]), read_scenario(r.scenarios[1]),
                                 read_scenario(r.scenarios[2]), read_scenario(r.scenarios[3]),
                                 read_scenario(r.scenarios[4])};
  std::string why;
  if (!r.options.IsValid(&why)) throw core::Failure("study learned: " + why);
  try {
    check_learned_scenarios(sc);
  } catch (const std::invalid_argument& e) {
    throw core::Failure("study learned: " + std::string(e.what()));
  }
  prepare_output(r.out);

  LearnedStudy s;
  try {
    s = run_learned_study(sc, r.options, hooks.progress);
  } catch (const std::invalid_argument& e) {
    throw core::Failure(e.what());
  }
  LearnedStudyContext c;
  c.command = learned_command(r);
  for (const auto& f : r.scenarios) c.scenario_files.push_back(display_path(r.source_dir, f));
  show_tables(hooks,
              fmt::format("Table 1 ({}):\n{}\n", s.table1.track, results::to_markdown(learned_table1_text(s))) +
                  fmt::format("Table 2 ({}), after the radius change at {:g} s:\n{}\n", s.table2.track,
                              s.table2.change_t_s, results::to_markdown(learned_table2_text(s, true))) +
                  fmt::format("{}\n", results::to_markdown(learned_table2_cost_text(s))) +
                  fmt::format("Table 3 ({}):\n{}", s.table3.track,
                              results::to_markdown(learned_table3_text(s))));
  try {
    return {write_learned_outputs(s, c, r.out), s.wall_s};
  } catch (const std::exception& e) {
    throw core::Failure(fmt::format("{}: {}", r.out, e.what()));
  }
}

}  // namespace odotune::studies
