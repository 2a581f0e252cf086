// The --controller-out flags that calibrate and diagnose share
// (odotune/jobs/controller_export.h checks them together and writes the file).
#pragma once

#include <CLI/CLI.hpp>

#include <odotune/jobs/controller_export.h>

namespace odotune::cli {

// --controller-out, --controller, --controller-form, --controller-name; with
// `nominal_flags` also --nominal-wheel-radius-m and --nominal-wheel-base-m.
void add_controller_options(CLI::App* sub, jobs::ControllerRequest& request, bool nominal_flags);

}  // namespace odotune::cli
