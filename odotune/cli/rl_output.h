// The robot_localization replay's flags (shared by eval and tune) and what
// the two commands print for it.
#pragma once

#include <vector>

#include <CLI/CLI.hpp>

#include <odotune/jobs/rl_job.h>
#include <odotune/jobs/rl_track_job.h>

namespace odotune::cli {

// The robot_localization flags are in three help groups (CLI11's
// Option::group), which say what each applies to: a command refuses, by
// name, a given flag whose group does not apply to what it runs (tune:
// cmd_tune.cpp; eval: cmd_eval.cpp), so a new flag needs no list of names.
inline constexpr const char* kRlGroup = "robot_localization (--rl-params)";
inline constexpr const char* kRlBagGroup = "robot_localization on a bag (--rl-params --bag)";
inline constexpr const char* kRlTrackGroup = "robot_localization on tracks (--rl-params --track)";

// The options of `app` given on the command line, in the order they were
// registered.
std::vector<const CLI::Option*> given_options(const CLI::App& app);

// --rl-params, --node, --filter (kRlGroup); --bag, --tf, --gps-topic,
// --navsat-params, --remap, --gps-heading-fit (kRlBagGroup).
void add_rl_source_options(CLI::App* sub, jobs::RlSource& src);
// `eval --keys`: each key of the file with what the replay makes of it, then the notes.
void print_rl_keys(const rlnode::RlParams& p);

// A track's inputs (kRlTrackGroup): --calibration, --odometry, --fix-sigma-m,
// --twist-variance, --gyro-variance.
void add_rl_track_options(CLI::App* sub, jobs::RlTrackSource& src);

void print_rl_eval(const jobs::RlEvalOutcome& o);
void print_rl_track_eval(const jobs::RlTrackEvalOutcome& o);
void print_rl_track_tune(const jobs::RlTuneRequest& r, const jobs::RlTrackTuneOutcome& o);
void print_rl_tune(const jobs::RlTuneRequest& r, const jobs::RlTuneOutcome& o);

}  // namespace odotune::cli
