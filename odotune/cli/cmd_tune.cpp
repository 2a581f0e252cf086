// odotune tune: tune one EKF noise model, one particle-filter calibrator's
// settings, or the velocity-fusion UKF's noise, on one or more tracks (odotune/jobs/tune_command.h runs it and writes the
// files; odotune/cli/tune_output.h prints the result).
#include <algorithm>
#include <array>
#include <cstdio>
#include <string_view>
#include <variant>

#include <fmt/format.h>

#include <odotune/cli/choices.h>
#include <odotune/cli/commands.h>
#include <odotune/cli/output.h>
#include <odotune/cli/progress.h>
#include <odotune/cli/rl_output.h>
#include <odotune/cli/tune_output.h>
#include <odotune/core/failure.h>
#include <odotune/jobs/tune_command.h>
#include <odotune/tuner/nlopt_solver.h>

namespace odotune::cli {
namespace {

// The help group of the flags of the tunes on tracks (EKF models,
// calibrators, UKF), which `tune --rl-params` refuses by name; the
// robot_localization flags are in rl_output.h's groups, the flags every tune
// takes in CLI11's default group (--track too: the tunes on tracks and
// --rl-params with --track take it).
constexpr const char* kTrackTuneGroup = "EKF, calibrator and UKF tunes (--track)";

// --format: the form of the robot_localization file --config-out writes.
enum class ParamsForm { ros2, ros1 };
constexpr std::array<ParamsForm, 2> kAllParamsForms = {ParamsForm::ros2, ParamsForm::ros1};
std::string_view to_string(ParamsForm f) { return f == ParamsForm::ros1 ? "ros1" : "ros2"; }

// --grid: "none" (no grid stage) or levels in decades, "-2,0,2".
std::vector<double> parse_grid_levels(const std::string& text) {
  if (text == "none") return {};
  std::vector<double> levels;
  std::size_t at = 0;
  while (at <= text.size()) {
    const std::size_t comma = std::min(text.find(',', at), text.size());
    const std::string item = text.substr(at, comma - at);
    try {
      std::size_t used = 0;
      levels.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw CLI::ValidationError(
          fmt::format("--grid {}: expected none or decades separated by commas, e.g. -2,0,2", text));
    }
    at = comma + 1;
  }
  return levels;
}

// The flags of `tune --rl-params` as given, checked against what the run
// applies to by their help groups (a flag of the tunes on tracks, a bag's
// flag on tracks or a track's on a bag is refused by name), and the command
// line they make, in the order the flags were registered: the tuned file's
// header quotes it.
std::string rl_tune_command_line(const CLI::App& sub, bool on_tracks) {
  std::string command = "odotune tune";
  for (const CLI::Option* opt : given_options(sub)) {
    const std::string& name = opt->get_name();
    const std::string& group = opt->get_group();
    if (group == kTrackTuneGroup)
      throw core::Failure(fmt::format("tune: {} does not apply to --rl-params (robot_localization's EKF)",
                                      name));
    if (on_tracks ? group == kRlBagGroup : (group == kRlTrackGroup || name == "--track"))
      throw core::Failure(fmt::format("tune: {} does not apply to --rl-params with {}", name,
                                      on_tracks ? "--track" : "--bag"));
    command += " " + name;
    if (opt->get_expected_min() == 0) continue;  // a flag: its name says it
    for (const std::string& v : opt->results()) command += " " + v;
  }
  return command;
}

// Without --rl-params every robot_localization flag (by its help group,
// rl_output.h) is refused by name, as eval does.
void check_track_tune_flags(const CLI::App& sub) {
  for (const CLI::Option* opt : given_options(sub)) {
    const std::string& group = opt->get_group();
    if (group == kRlGroup || group == kRlBagGroup || group == kRlTrackGroup)
      throw core::Failure(fmt::format("tune: {} applies to --rl-params only", opt->get_name()));
  }
}

// tune --rl-params, on the bag (--bag) or on tracks (--track).
void run_rl_tune_command(const jobs::TuneCommandRequest& req, jobs::RlTuneRequest r,
                         const jobs::RlTrackSource& track_src, const CLI::App& sub) {
  const bool on_tracks = r.src.bag.empty() && !req.tracks.empty();
  r.command_line = rl_tune_command_line(sub, on_tracks);
  static_cast<jobs::SolverSettings&>(r) = req;
  r.options.folds = req.fix_cv.folds;
  r.options.block_s = req.fix_cv.block_s;
  r.json_out = req.json_out;
  r.config_out = req.config_out;
  InterruptGuard interrupt;
  Progress progress("tune", "evaluations");
  r.progress = [&progress](long done, long total) { progress.update(done, total); };
  r.stop = interrupt.flag();
  if (on_tracks) {
    jobs::RlTrackSource src = track_src;
    src.params_file = r.src.params_file;
    src.node_name = r.src.node_name;
    src.filter = r.src.filter;
    src.tracks = {req.tracks.begin(), req.tracks.end()};
    const jobs::RlTrackTuneOutcome o = jobs::run_rl_track_tune(r, src);
    progress.finish();
    if (interrupt.raised()) std::fprintf(stderr, "odotune: interrupted; reporting the best so far\n");
    print_rl_track_tune(r, o);
    if (interrupt.raised()) throw core::Failure("interrupted", 130);
    return;
  }
  const jobs::RlTuneOutcome o = jobs::run_rl_tune(r);
  progress.finish();
  if (interrupt.raised()) std::fprintf(stderr, "odotune: interrupted; reporting the best so far\n");
  print_rl_tune(r, o);
  if (interrupt.raised()) throw core::Failure("interrupted", 130);
}

// --solver: pso or nlopt:NAME, parsed into req->solver.
void add_solver_option(CLI::App* sub, const std::shared_ptr<jobs::TuneCommandRequest>& req) {
  std::string algos;
  for (const auto& a : tuner::nlopt_algorithm_names()) algos += " " + a;
  sub->add_option_function<std::string>(
         "--solver",
         [req](const std::string& text) {
           std::string why;
           const std::optional<tuner::SolverChoice> solver = tuner::SolverChoice::parse(text, &why);
           if (!solver) throw CLI::ValidationError("--solver", why);
           req->solver = *solver;
         },
         "pso or nlopt:NAME, NAME one of" + algos)
      ->default_str("pso");
}

// The calibrators' particle filter and external velocities.
void add_calibrator_options(CLI::App* sub, jobs::TuneCommandRequest& req) {
  add_enum_option(sub, "--resampler", req.resampler, filters::kAllResamplers,
                  "calibrators: the resampling scheme (default systematic)")
      ->group(kTrackTuneGroup);
  add_enum_option(sub, "--policy", req.policy, filters::kAllResamplePolicies,
                  "calibrators: the resampling policy (default neff)")
      ->group(kTrackTuneGroup);
  sub->add_option("--pf-particles", req.pf_particles,
                  "calibrators: N (pf-calib) or initial N (adaptive-pf-calib); default the paper's "
                  "5000 / 8000")
      ->check(CLI::PositiveNumber)
      ->group(kTrackTuneGroup);
  sub->add_option("--pf-seed", req.pf_seed, "calibrators: the particle filter's own seed (default 1)")
      ->group(kTrackTuneGroup);
  sub->add_option("--ext-from-gt", req.ext_from_gt_hz,
                  "calibrators: derive the external velocities from the ground truth at this rate [Hz] "
                  "instead of the tracks' v_ext/w_ext")
      ->check(CLI::PositiveNumber)
      ->group(kTrackTuneGroup);
}

// robot_localization tuning (--rl-params): the span (kRlBagGroup: a bag's
// clock), fitness, search space and outputs (kRlGroup).
void add_rl_tune_options(CLI::App* sub, jobs::RlTuneRequest& rl) {
  sub->add_option("--until", rl.until_s,
                  "--rl-params: tune on the recording before this many seconds; the rest is scored as held out")
      ->check(CLI::PositiveNumber)
      ->group(kRlBagGroup);
  add_enum_option(sub, "--fitness", rl.options.fitness, objectives::kAllRlFitnesses,
                  "--rl-params: both (held-out fixes and simulated GPS outages, each relative to the file's "
                  "values; default), outage, heldout-fixes (mode 8 on this filter), or an innovation statistic "
                  "(docs/husky.md, \"Methods tried\"): innovation-nll, nis, whiteness, heldout-nll")
      ->group(kRlGroup);
  add_enum_option(sub, "--space", rl.options.space, objectives::kAllRlNoiseSpaces,
                  "--rl-params: search a factor per diagonal entry of the process noise (default) or per block")
      ->group(kRlGroup);
  sub->add_flag_callback(
         "--no-input-covariances", [&rl] { rl.options.input_covariances = false; },
         "--rl-params: do not search factors on the inputs' message covariances")
      ->group(kRlGroup);
  sub->add_flag("--ukf-constants", rl.options.ukf_constants,
                "--rl-params with ukf_node: also search factors on its alpha, 15 + kappa and beta")
      ->group(kRlGroup);
  sub->add_option("--from", rl.from_s,
                  "--rl-params: tune on the recording after this many seconds (the bag cut there) and judge "
                  "before it: GPS fused for its first 60 s, then an outage; and every 5th fix held out")
      ->check(CLI::PositiveNumber)
      ->group(kRlBagGroup);
  sub->add_option("--outage", rl.options.outage_s,
                  "--rl-params: lengths of the simulated GPS outages [s], comma-separated (default 30,60)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber)
      ->group(kRlGroup);
  sub->add_option("--outage-every", rl.options.outage_stride_s,
                  "--rl-params: an outage of each length starts every this many seconds (default 10)")
      ->check(CLI::PositiveNumber)
      ->group(kRlGroup);
  sub->add_flag_callback(
         "--allow-worse-heldout", [&rl] { rl.options.keep_heldout = false; },
         "--rl-params: let the tune make the held-out-fix error worse than the file's (by default a "
         "candidate that does scores above the file's own values)")
      ->group(kRlGroup);
  sub->add_flag("--subtract-fix-variance", rl.options.subtract_fix_variance,
                "--rl-params: score the held-out fixes and the outages by the error with the fixes' own "
                "variance taken out, sqrt(RMSE^2 - mean(var_x + var_y)), which estimates the error against "
                "the true position; for fixes whose variances are their true ones (docs/robot-localization.md)")
      ->group(kRlGroup);
  sub->add_option("--starts", rl.starts,
                  "--rl-params: refinements from seeds --seed, --seed + 1, …; the lowest tuning fitness is "
                  "written, the spread printed (default 1)")
      ->check(CLI::Range(1, 1000))
      ->group(kRlGroup);
  sub->add_option(
         "--starts-out", rl.starts_out,
         "--rl-params: also write every start's file into this folder as ekf-seed<K>.yaml (ukf-seed<K>.yaml for the UKF)")
      ->group(kRlGroup);
  sub->add_option_function<std::string>(
         "--grid",
         [&rl](const std::string& text) {
           if (!text.empty()) rl.search.grid_levels = parse_grid_levels(text);  // "": the default levels
         },
         "--rl-params: the first, deterministic stage: each block's factor one of 10^LEVEL, "
         "comma-separated decades (default -2,0,2), or none")
      ->group(kRlGroup);
  sub->add_option("--refine", rl.search.refine_decades,
                  "--rl-params: a seeded refinement of the parameters the grid determined, within this many "
                  "decades of its best (default 0: none, the tune is the same from every seed)")
      ->check(CLI::NonNegativeNumber)
      ->group(kRlGroup);
  sub->add_option("--prior", rl.options.prior_weight,
                  "--rl-params: weight of a prior toward the file's values, added as weight × mean (log10 "
                  "factor)² (default 0)")
      ->check(CLI::NonNegativeNumber)
      ->group(kRlGroup);
  add_choice_option(
      sub, "--format", [&rl](ParamsForm f) { rl.ros1_out = f == ParamsForm::ros1; }, kAllParamsForms,
      "--rl-params: --config-out as ros2 (default) or ros1 parameters")
      ->group(kRlGroup);
  sub->add_option("--end", rl.end_s,
                  "--rl-params: ignore the recording after this many seconds (the held-out span ends there)")
      ->check(CLI::PositiveNumber)
      ->group(kRlBagGroup);
  sub->add_option("--config-out-ros1", rl.config_out_ros1,
                  "--rl-params: also write the ROS 1 form to this file")
      ->group(kRlGroup);
}

// The tune command itself: robot_localization tuning with --rl-params, else
// the tracks' tune, printed (the best so far after Ctrl-C).
void run_tune_subcommand(const jobs::TuneCommandRequest& req, const jobs::RlTuneRequest& rl,
                         const jobs::RlTrackSource& rl_track, int threads, const CLI::App& sub) {
  apply_threads(threads);
  if (!rl.src.params_file.empty()) {
    run_rl_tune_command(req, rl, rl_track, sub);
    return;
  }
  if (req.tracks.empty()) throw core::Failure("tune: expected --track, or --rl-params with --bag");
  check_track_tune_flags(sub);
  jobs::TuneCommandRequest r = req;
  InterruptGuard interrupt;  // Ctrl-C stops the tune: the best so far is printed and written
  Progress progress("tune", "evaluations");
  r.progress = [&progress](long done, long total) { progress.update(done, total); };
  r.stop = interrupt.flag();
  r.report = [&](const jobs::TuneCommandOutcome& outcome) {
    progress.finish();
    if (interrupt.raised()) std::fprintf(stderr, "odotune: interrupted; reporting the best so far\n");
    std::visit([](const auto& o) { print_tune_outcome(o); }, outcome);
  };
  jobs::run_tune_command(r);
  if (interrupt.raised()) throw core::Failure("interrupted", 130);
}

}  // namespace

void register_tune(CLI::App& app) {
  auto req = std::make_shared<jobs::TuneCommandRequest>();
  auto threads = std::make_shared<int>(0);
  auto* sub = app.add_subcommand(
      "tune", "Tune the EKF noise of one model, a particle-filter calibrator's settings, or the fusion UKF's "
              "noise, on tracks");
  sub->footer(
      "Example:\n"
      "  odotune tune --track data/tracks/track1.csv --model rq --mode 7 --seed 1 --json out.json\n"
      "  odotune tune --track a.csv --track b.csv --model gyro --solver nlopt:DIRECT_L --evals 3000\n"
      "  odotune tune --track wheelchair.csv --model adaptive-pf-calib --particles 16 --iterations 10 \\\n"
      "      --config-out pf.yaml\n"
      "EKF models: prints baseline and tuned RMSE/MAE/MAXE with the improvement in %. The baseline\n"
      "is the untuned configuration described in the README (alpha model, α1 = α2 = 0.01, σ_fix 60 mm).\n"
      "Calibrators (pf-calib, adaptive-pf-calib): tunes N_eff fraction, max-weight ratio, α,\n"
      "dispersion per particle and random-walk σ; the score weighs the final radius error,\n"
      "convergence time, the calibrated odometry's pose RMSE and the particle count\n"
      "(odotune/calibration/calibration_objective.h). The baseline is the paper's default settings;\n"
      "if they score better than the solver's best they are kept. Tracks need external velocities\n"
      "(v_ext, w_ext, or --ext-from-gt HZ) and ground truth, all of one robot. --config-out writes\n"
      "an odotune-pf-config/1 file (odotune/formats/pf_config_yaml.h).\n"
      "UKF (ukf): tunes the (V, W) fusion filter's process noise, static odometry variances, gyro\n"
      "variance and external-variance scale (odotune/learned/ukf_objective.h) for --mode's error of\n"
      "the fused pose against ground truth (tracks need it); the baseline is the default noise.\n"
      "--config-out writes an odotune-ukf-config/1 file (odotune/formats/ukf_config_yaml.h).\n"
      "robot_localization (--rl-params FILE --bag BAG): tunes the process noise of the robot's own ekf_node\n"
      "(factors on its process_noise_covariance, per diagonal entry or per block) and, as advice, factors on\n"
      "each input's message covariance, by held-out GPS fixes and simulated GPS outages; --config-out\n"
      "writes the user's file with the tuned values and the held-out scores in comments:\n"
      "  odotune tune --rl-params husky_ekf.yaml --bag test1.bag --tf imu_link=0,-0.3,0.52,1.5707963,0,-1.5707963 \\\n"
      "      --gps-heading-fit 60 --until 197.6 --fitness both --config-out ekf.yaml\n"
      "  or on tracks (several tuned together; their ground truth is not used; docs/robot-localization.md):\n"
      "  odotune tune --rl-params user.yaml --track robot1-fixes.csv --track robot2-fixes.csv --config-out tuned.yaml");
  sub->add_option("--track", req->tracks, "track file (repeat for several; fitness = mean over tracks)");
  add_enum_option(sub, "--model", req->model, objectives::kAllTunedModels,
                  "the EKF noise model (rq, alpha, gyro), a particle-filter calibrator (pf-calib, "
                  "adaptive-pf-calib) or the fusion UKF (ukf); robot_localization's (rl-ekf, rl-ukf) are tuned "
                  "with --rl-params (default rq)")
      ->group(kTrackTuneGroup);
  add_fitness_mode_option(
      sub, [req](objectives::FitnessMode m) { req->mode = m; },
      "EKF/UKF fitness mode (number or name) against ground truth: 1 rmse, 2 mae, 3 maxe, 4 rmse+mae, "
      "5 rmse+maxe, 6 mae+maxe, 7 rmse+mae+maxe (default); EKF without ground truth, cross-validating over the "
      "position fixes: 8 fix-rmse, held-out fix RMSE (the default when a track has no ground truth), 9 fix-nll, "
      "held-out fix NLL (needs the fixes' variances right)")
      ->group(kTrackTuneGroup);
  sub->add_option("--cv-folds", req->fix_cv.folds, "modes 8, 9: folds of the fix cross-validation (default 5)")
      ->check(CLI::Range(2, 100));
  sub->add_option("--cv-block", req->fix_cv.block_s,
                  "modes 8, 9: fixes within blocks of this many seconds are held out together (default 1)")
      ->check(CLI::PositiveNumber);
  add_solver_option(sub, req);
  sub->add_option("--seed", req->seed, "random seed (same seed ⇒ same result)");
  sub->add_option("--particles", req->particles, "PSO swarm size")->check(CLI::PositiveNumber);
  sub->add_option("--iterations", req->iterations, "PSO iterations")->check(CLI::NonNegativeNumber);
  sub->add_option("--evals", req->evaluations,
                  "NLopt evaluation budget (default: particles × (iterations + 1), as PSO)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--json", req->json_out, "write the result as JSON to this file");
  sub->add_option("--config-out", req->config_out,
                  "write the tuned configuration (YAML: EKF models for eval --config, calibrators "
                  "odotune-pf-config/1, ukf odotune-ukf-config/1)");
  add_calibrator_options(sub, *req);
  auto rl = std::make_shared<jobs::RlTuneRequest>();
  auto rl_track = std::make_shared<jobs::RlTrackSource>();
  add_rl_source_options(sub, rl->src);
  add_rl_tune_options(sub, *rl);
  add_rl_track_options(sub, *rl_track);
  add_threads_option(sub, threads.get());

  sub->callback([req, rl, rl_track, threads, sub] {
    run_tune_subcommand(*req, *rl, *rl_track, *threads, *sub);
  });
}

}  // namespace odotune::cli
