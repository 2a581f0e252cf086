// Registration of the odotune subcommands. Each command lives in its own
// cmd_*.cpp and adds itself to the CLI11 app here; the CLI layer is the only
// one that reads flags: a command fills a request, calls one function of
// jobs/ or studies/ and prints its result (odotune/cli/README.md).
#pragma once

#include <CLI/CLI.hpp>

namespace odotune::cli {

// Each register_* adds one subcommand (with --help text and an example) and
// sets its callback. Callbacks report failure by throwing core::Failure
// (one clear line, non-zero exit) or any std::exception.
void register_simulate(CLI::App& app);
void register_import(CLI::App& app);
void register_tune(CLI::App& app);
void register_eval(CLI::App& app);
void register_demo(CLI::App& app);
void register_fixes(CLI::App& app);
void register_grid(CLI::App& app);
void register_report(CLI::App& app);
void register_export(CLI::App& app);
void register_diagnose(CLI::App& app);
void register_calibrate(CLI::App& app);
void register_study(CLI::App& app);
void register_learn(CLI::App& app);

// Runs the CLI; returns the process exit code.
int run(int argc, char** argv);

}  // namespace odotune::cli
