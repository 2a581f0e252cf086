// odotune fixes: add synthetic absolute position fixes to a track
// (odotune/jobs/fixes_job.h); this file reads the flags and prints.
#include <memory>

#include <fmt/format.h>

#include <odotune/cli/commands.h>
#include <odotune/jobs/fixes_job.h>

namespace odotune::cli {

void register_fixes(CLI::App& app) {
  auto req = std::make_shared<jobs::FixesRequest>();
  auto* sub = app.add_subcommand("fixes",
                                 "Add position fixes made from ground truth (the study's APS: 1 Hz, σ 60 mm)");
  sub->footer("Example:\n"
              "  odotune import optiodom RUN.csv -o run.csv\n"
              "  odotune fixes run.csv -o run-aps.csv --rate-hz 1 --sigma-m 0.06 --seed 7\n"
              "  odotune tune --track run-aps.csv --model alpha\n"
              "Existing aps_x/aps_y columns are replaced.");
  sub->add_option("track", req->track, "input track")->required();
  sub->add_option("-o,--output", req->output, "output track")->required();
  sub->add_option("--rate-hz", req->options.rate_hz, "fix frequency [Hz]");
  sub->add_option("--sigma-m", req->options.sigma_m, "noise σ per axis [m]");
  sub->add_option("--seed", req->options.seed, "noise seed");
  sub->add_flag("!--no-variances", req->options.variances,
                "do not write the fixes' variances (aps_var_x, aps_var_y = σ², written by default)");
  sub->callback([req] { fmt::print("{}: {}\n", req->output, jobs::run_fixes(*req)); });
}

}  // namespace odotune::cli
