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
void add_rl_source_options(CLI::App* sub, RlSource& src);

// A track's inputs: --odometry, --fix-sigma-m, --twist-variance, --gyro-variance, --calibration.
void add_rl_track_options(CLI::App* sub, RlTrackSource& src);
// The flags that apply to --rl-params with --track.
inline constexpr const char* kRlTrackFlags[] = {"--odometry", "--fix-sigma-m", "--twist-variance",
                                                "--gyro-variance", "--calibration"};

void print_rl_eval(const RlEvalOutcome& o);
void print_rl_track_eval(const RlTrackEvalOutcome& o);
void print_rl_track_tune(const RlTuneRequest& r, const RlTrackTuneOutcome& o);
void print_rl_tune(const RlTuneRequest& r, const RlTuneOutcome& o);

}  // namespace odotune::cli
