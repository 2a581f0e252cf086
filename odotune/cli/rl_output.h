// The robot_localization replay's flags (shared by eval and tune) and what
// the two commands print for it.
#pragma once

#include <CLI/CLI.hpp>

#include <odotune/jobs/rl_job.h>
#include <odotune/jobs/rl_track_job.h>

namespace odotune::cli {

// --rl-params, --bag, --node, --tf, --gps-topic, --gps-heading-fit.
// `eval --keys`: each key of the file with what the replay makes of it, then the notes.
void print_rl_keys(const rlnode::RlParams& p);
void add_rl_source_options(CLI::App* sub, jobs::RlSource& src);

// A track's inputs: --odometry, --fix-sigma-m, --twist-variance, --gyro-variance, --calibration.
void add_rl_track_options(CLI::App* sub, jobs::RlTrackSource& src);
// The flags that apply to --rl-params with --track.
inline constexpr const char* kRlTrackFlags[] = {"--odometry", "--fix-sigma-m", "--twist-variance",
                                                "--gyro-variance", "--calibration"};

void print_rl_eval(const jobs::RlEvalOutcome& o);
void print_rl_track_eval(const jobs::RlTrackEvalOutcome& o);
void print_rl_track_tune(const jobs::RlTuneRequest& r, const jobs::RlTrackTuneOutcome& o);
void print_rl_tune(const jobs::RlTuneRequest& r, const jobs::RlTuneOutcome& o);

}  // namespace odotune::cli
