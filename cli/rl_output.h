// The robot_localization replay's flags (shared by eval and tune) and what
// the two commands print for it.
#pragma once

#include <CLI/CLI.hpp>

#include "jobs/rl_job.h"

namespace odotune::cli {

// --rl-params, --bag, --node, --tf, --gps-topic, --gps-heading-fit.
void add_rl_source_options(CLI::App* sub, RlSource& src);

void print_rl_eval(const RlEvalOutcome& o);
void print_rl_tune(const RlTuneRequest& r, const RlTuneOutcome& o);

}  // namespace odotune::cli
