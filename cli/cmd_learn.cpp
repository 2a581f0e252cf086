// odotune learn train|eval|retrain: the learned odometry of Fariña, Acosta,
// Toledo & Acosta, "Improving Odometric Model Performance Based on LSTM
// Networks", Sensors 2023, 23, 961, on recorded or simulated tracks. This
// file reads the flags, shows the progress and prints; the work (training,
// scoring, retraining, the model file, JSON and CSV) is studies/learn_job.h.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/commands.h"
#include "cli/output.h"
#include "cli/progress.h"
#include "studies/learn_job.h"

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

}  // namespace

void register_learn(CLI::App& app) {
  auto* learn = app.add_subcommand(
      "learn",
      "Learned (LSTM) odometry with a slip detector and online retraining (Fariña et al., Sensors 2023)");
  learn->require_subcommand(1);
  learn->footer(
      "Examples:\n"
      "  odotune learn train --track a.csv --track b.csv --slip-track slip.csv --model-out model.json\n"
      "  odotune learn eval --track held_out.csv --model model.json --json eval.json\n"
      "  odotune learn retrain --track changed.csv --model model.json --model-out model2.json --json retrain.json");
  auto train = std::make_shared<LearnTrainRequest>();
  auto* t = learn->add_subcommand("train",
                                  "Train the V and W nets (and the slip detector) on tracks with ground truth");
  t->add_option("--track", train->tracks, "track with ground truth (repeat for several)")->required();
  t->add_option("--slip-track", train->slip_tracks,
                "track with motor power and slip, to train the slip detector on (repeat for several)");
  t->add_option("--model-out", train->model_out, "model file to write (JSON, odotune-learned/1)")->required();
  t->add_option("--seed", train->seed, "seed of the initial weights")->default_val(train->seed);
  t->add_option("--iterations", train->iterations, "Ceres iterations per net")->default_val(train->iterations);
  t->add_option("--slip-iterations", train->slip_iterations,
                "Ceres iterations per slip-detector net (default: --iterations)")
      ->check(CLI::PositiveNumber);
  t->add_option("--previous-noise", train->previous_noise,
                "σ of the noise on the teacher-forced previous V [m/s] and W [rad/s] while training "
                "(default 0)")
      ->check(CLI::NonNegativeNumber);
  t->add_option("--rate-hz", train->rate_hz, "network rate [Hz] (paper: 10)")->default_val(train->rate_hz);
  auto target = std::make_shared<std::string>("velocity");
  t->add_option("--target", *target,
                "what the nets output: velocity (the paper's) or correction (added to the nominal kinematic "
                "velocity; an untrained net reproduces the kinematics)")
      ->check(CLI::IsMember({"velocity", "correction"}))
      ->default_val(*target);
  auto validation = std::make_shared<std::string>("chronological");
  t->add_option("--validation", *validation,
                "what the nets are validated on: chronological (the last 30 % of each track) or recordings "
                "(the last 30 % of the tracks as given, held out whole)")
      ->check(CLI::IsMember({"chronological", "recordings"}))
      ->default_val(*validation);
  t->add_option("--threads", train->threads, "threads evaluating the windows (results do not depend on it)")
      ->check(CLI::PositiveNumber);
  t->callback([train, t, target, validation] {
    parse_learned_target(*target, &train->target);  // IsMember checked the names
    parse_learned_validation(*validation, &train->validation);
    std::string& c = train->command;
    c = "odotune learn train";
    for (const auto& f : train->tracks) c += " --track " + f;
    for (const auto& f : train->slip_tracks) c += " --slip-track " + f;
    c += " --model-out " + train->model_out +
         fmt::format(" --seed {} --iterations {}", train->seed, train->iterations);
    if (train->slip_iterations > 0) c += fmt::format(" --slip-iterations {}", train->slip_iterations);
    if (train->previous_noise >= 0.0) c += fmt::format(" --previous-noise {}", train->previous_noise);
    if (t->count("--rate-hz") > 0) c += fmt::format(" --rate-hz {}", train->rate_hz);
    if (t->count("--target") > 0) c += fmt::format(" --target {}", to_string(train->target));
    if (t->count("--validation") > 0) c += fmt::format(" --validation {}", to_string(train->validation));
    print_lines(learn_train_lines(with_progress("learn train", "nets", [&](const LearnProgress& p) {
      return run_learn_train(*train, p);
    })));
  });

  auto eval = std::make_shared<LearnEvalRequest>();
  auto* e = learn->add_subcommand(
      "eval", "Score the learned and the kinematic odometry against a track's ground truth");
  e->add_option("--track", eval->track, "track with ground truth")->required();
  e->add_option("--model", eval->model, "model file (odotune learn train --model-out)")->required();
  e->add_option("--json", eval->json, "write the errors as JSON (blocks learned and kinematic)");
  e->add_option("--csv", eval->csv, "write the velocities and dead-reckoned poses per step as CSV");
  e->callback([eval] { print_lines(learn_eval_lines(run_learn_eval(*eval))); });

  auto retrain = std::make_shared<LearnRetrainRequest>();
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
  r->add_flag("--static-covariance", retrain->static_covariance,
              "ignore the model's slip detector: static odometry variances from the validation MAEs");
  r->add_option("--threads", retrain->threads, "threads evaluating the windows (results do not depend on it)")
      ->check(CLI::PositiveNumber);
  r->callback([retrain] {
    retrain->command = "odotune learn retrain --track " + retrain->track + " --model " + retrain->model +
                       fmt::format(" --every {} --iterations {}", retrain->every, retrain->iterations);
    print_lines(learn_retrain_lines(with_progress("learn retrain", "runs", [&](const LearnProgress& p) {
      return run_learn_retrain(*retrain, p);
    })));
  });
}

}  // namespace odotune::cli
