// odotune learn train|eval|retrain: the learned odometry of Fariña, Acosta,
// Toledo & Acosta, "Improving Odometric Model Performance Based on LSTM
// Networks", Sensors 2023, 23, 961, on recorded or simulated tracks. This
// file reads the flags, shows the progress and prints; the work (training,
// scoring, retraining, the model file, JSON and CSV) is odotune/studies/learn_job.h.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <odotune/cli/choices.h>
#include <odotune/cli/commands.h>
#include <odotune/cli/output.h>
#include <odotune/cli/progress.h>
#include <odotune/studies/learn_job.h>

namespace odotune::cli {

namespace {

// Runs `job` with a progress line on stderr, made at the job's first step
// (after its inputs have loaded) and cleared when it returns.
template <class Job>
auto with_progress(const char* label, const char* unit, Job job) {
  std::optional<Progress> bar;
  auto outcome = job([&](long done, long total) {
    if (!bar) bar.emplace(label, unit);
    bar->update(done, total);
  });
  if (bar) bar->finish();
  return outcome;
}

// The flags of `learn train`.
void add_train_options(CLI::App* t, studies::LearnTrainRequest& r) {
  t->add_option("--track", r.tracks, "track with ground truth (repeat for several)")->required();
  t->add_option(
      "--slip-track", r.slip_tracks,
      "track with ground truth to train the slip detector on: it reads the motor power, else the commands "
      "beside the wheels, else the odometry alone (repeat for several)");
  t->add_option("--model-out", r.model_out, "model file to write (JSON, odotune-learned/1)")->required();
  t->add_option("--seed", r.seed, "seed of the initial weights")->default_val(r.seed);
  t->add_option("--iterations", r.iterations,
                "Ceres iterations per net (correction nets: the most their early stopping allows)")
      ->default_val(r.iterations);
  t->add_option("--slip-iterations", r.slip_iterations,
                "Ceres iterations per slip-detector net (default: --iterations)")
      ->check(CLI::PositiveNumber);
  t->add_option("--previous-noise", r.previous_noise,
                "the paper's nets: σ of the noise on the teacher-forced previous V [m/s] and W [rad/s] while "
                "training (default 0)")
      ->check(CLI::NonNegativeNumber);
  t->add_option("--rate-hz", r.rate_hz, "network rate [Hz] (paper: 10)")->default_val(r.rate_hz);
  add_enum_option(t, "--input", r.input, tracks::kAllOdometryInputs,
                  "the odometry the nets read: wheels, twist (a measured v, w) or commands (default: each "
                  "track's own, docs/track-format.md)");
  add_enum_option(t, "--target", r.target,
                  {learned::LearnedTarget::correction, learned::LearnedTarget::velocity},
                  "what the nets output: correction (added to the kinematic odometry; an untrained net is the "
                  "kinematics) or velocity (the paper's nets on wheel increments)")
      ->default_str(std::string(learned::to_string(r.target)));
  add_enum_option(
      t, "--validation", r.validation,
      {learned::LearnedValidation::recordings, learned::LearnedValidation::blocks,
       learned::LearnedValidation::chronological},
      "what the nets are validated on: correction nets recordings (default with 2 tracks or more) or "
      "blocks (of --block-s); the paper's chronological (default: the last 30 % of each track) or "
      "recordings");
  learned::SelectionOptions& so = r.selection;
  t->add_option("--block-s", so.block_s, "--validation blocks: the blocks' length [s]")
      ->default_val(so.block_s)
      ->check(CLI::PositiveNumber);
  t->add_option("--folds", so.max_folds, "correction nets: most folds of the cross-validation")
      ->default_val(so.max_folds)
      ->check(CLI::Range(2, 100));
  t->add_option("--patience", so.training.early_stopping_patience,
                "correction nets: iterations without a better validation MAE before a fit stops")
      ->default_val(so.training.early_stopping_patience)
      ->check(CLI::PositiveNumber);
  t->add_option("--units", so.units, "correction nets: the LSTM sizes to choose from (3, 5, 8)")
      ->delimiter(',')
      ->default_str("3,5")
      ->check(CLI::IsMember({3, 5, 8}));
  t->add_option("--windows", so.windows, "correction nets: the window lengths to choose from [steps]")
      ->delimiter(',')
      ->default_str("10,20")
      ->check(CLI::Range(2, 256));
  t->add_option("--decays", so.weight_decays, "correction nets: the L2 weight decays to choose from")
      ->delimiter(',')
      ->default_str("0,10")
      ->check(CLI::NonNegativeNumber);
  add_enum_list_option(t, "--features", so.features,
                       {learned::LearnedFeatures::channel, learned::LearnedFeatures::both},
                       "correction nets: the feature sets to choose from (channel: each net its own channel of "
                       "the odometry; both: v and w for either)")
      ->default_str("channel,both");
  t->add_flag(
      "--no-gyro", [&so](std::int64_t) { so.use_gyro = false; },
      "correction nets: do not read the track's gyro");
  t->add_option("--threads", r.threads, "threads evaluating the windows (results do not depend on it)")
      ->check(CLI::PositiveNumber);
}

// The command line that regenerates the model (its provenance.created_by):
// the tracks and output, and every flag given.
std::string train_command(const studies::LearnTrainRequest& r, const CLI::App& t) {
  std::string c = "odotune learn train";
  for (const auto& f : r.tracks) c += " --track " + f;
  for (const auto& f : r.slip_tracks) c += " --slip-track " + f;
  c += " --model-out " + r.model_out + fmt::format(" --seed {} --iterations {}", r.seed, r.iterations);
  for (const CLI::Option* o : t.get_options()) {
    const std::string name = o->get_name();
    if (o->count() == 0 || name == "--track" || name == "--slip-track" || name == "--model-out" ||
        name == "--seed" || name == "--iterations" || name == "--help")
      continue;
    c += " " + name;
    if (o->get_type_size() != 0) c += " " + fmt::format("{}", fmt::join(o->results(), ","));
  }
  return c;
}

}  // namespace

void register_learn(CLI::App& app) {
  auto* learn = app.add_subcommand(
      "learn",
      "Learned (LSTM) odometry with a slip detector and online retraining (Fariña et al., Sensors 2023)");
  learn->require_subcommand(1);
  learn->footer(
      "Examples:\n"
      "  odotune learn train --track a.csv --track b.csv --slip-track slip.csv --model-out model.json\n"
      "  odotune learn train --track robot1.csv --track robot2.csv --input commands --model-out model.json\n"
      "  odotune learn eval --track held_out.csv --model model.json --calibration cal.yaml --fix-sigma-m 0.1\n"
      "  odotune learn eval --track held_out.csv --model model.json --json eval.json\n"
      "  odotune learn retrain --track changed.csv --model model.json --model-out model2.json --json retrain.json");
  auto train = std::make_shared<studies::LearnTrainRequest>();
  auto* t = learn->add_subcommand("train",
                                  "Train the V and W nets (and the slip detector) on tracks with ground truth");
  add_train_options(t, *train);
  t->callback([train, t] {
    train->command = train_command(*train, *t);
    print_lines(
        studies::learn_train_lines(with_progress("learn train", "fits", [&](const studies::LearnProgress& p) {
          return studies::run_learn_train(*train, p);
        })));
  });

  auto eval = std::make_shared<studies::LearnEvalRequest>();
  auto* e = learn->add_subcommand(
      "eval", "Score the learned and the kinematic odometry against a track's ground truth");
  e->add_option("--track", eval->track, "track with ground truth")->required();
  e->add_option("--model", eval->model, "model file (odotune learn train --model-out)")->required();
  e->add_option("--json", eval->json, "write the errors as JSON (blocks learned and kinematic)");
  e->add_option("--csv", eval->csv, "write the velocities and dead-reckoned poses per step as CSV");
  e->add_option("--from", eval->from_s, "score only the steps from this time on [s, the track's clock]");
  e->add_option("--until", eval->until_s, "score only the steps before this time [s]");
  e->add_option("--fix-sigma-m", eval->fix_sigma_m,
                "σ of the track's position fixes where they have no aps_var [m], for the fusion with them")
      ->check(CLI::PositiveNumber);
  e->add_option("--calibration", eval->calibration,
                "also score the kinematics calibrated by this file (odotune calibrate --method batch "
                "--config-out) on the same track");
  e->callback([eval] { print_lines(studies::learn_eval_lines(studies::run_learn_eval(*eval))); });

  auto retrain = std::make_shared<studies::LearnRetrainRequest>();
  auto* r = learn->add_subcommand(
      "retrain",
      "Run the UKF with online retraining over a track (and without), compare, save the retrained model");
  r->add_option("--track", retrain->track, "track with ground truth and external velocities")->required();
  r->add_option("--model", retrain->model, "model file to start from")->required();
  r->add_option("--model-out", retrain->model_out, "write the retrained model here");
  r->add_option("--json", retrain->json, "write the retrain events and the errors with and without retraining");
  r->add_option("--every", retrain->every, "retrain every N well-localised samples (paper: 300)")
      ->default_val(retrain->every);
  r->add_option("--iterations", retrain->iterations, "Ceres iterations per refit")
      ->default_val(retrain->iterations);
  r->add_option(
       "--ext-from-gt", retrain->ext_from_gt_hz,
       "derive the external velocities from the ground truth at this rate [Hz] (a reference such as the "
       "paper's Velodyne, where a dataset has only a pose reference)")
      ->check(CLI::Range(0.1, 100.0));
  r->add_option(
      "--until", retrain->until_s,
      "run and retrain on the steps before this time only [s] (judge the rest with learn eval --from)");
  r->add_flag("--static-covariance", retrain->static_covariance,
              "ignore the model's slip detector: static odometry variances from the validation MAEs");
  r->add_option("--threads", retrain->threads, "threads evaluating the windows (results do not depend on it)")
      ->check(CLI::PositiveNumber);
  r->callback([retrain] {
    retrain->command = "odotune learn retrain --track " + retrain->track + " --model " + retrain->model +
                       fmt::format(" --every {} --iterations {}", retrain->every, retrain->iterations);
    if (retrain->ext_from_gt_hz > 0)
      retrain->command += fmt::format(" --ext-from-gt {}", retrain->ext_from_gt_hz);
    if (retrain->until_s) retrain->command += fmt::format(" --until {}", *retrain->until_s);
    print_lines(studies::learn_retrain_lines(with_progress("learn retrain", "runs",
                                                           [&](const studies::LearnProgress& p) {
                                                             return studies::run_learn_retrain(*retrain, p);
                                                           })));
  });
}

}  // namespace odotune::cli
