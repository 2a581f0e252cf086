// odotune fixes: add synthetic absolute position fixes to a track.
#include <fmt/format.h>

#include "cli/commands.h"
#include "core/failure.h"
#include "cli/output.h"
#include "tracks/synthetic_fixes.h"
#include "tracks/track_io.h"

namespace odotune::cli {

namespace {
struct FixesArgs {
  std::string track, output;
  SyntheticFixOptions options;
};
}  // namespace

void register_fixes(CLI::App& app) {
  auto args = std::make_shared<FixesArgs>();
  auto* sub = app.add_subcommand(
      "fixes", "Add position fixes made from ground truth (the study's APS: 1 Hz, σ 60 mm)");
  sub->footer(
      "Example:\n"
      "  odotune import optiodom RUN.csv -o run.csv\n"
      "  odotune fixes run.csv -o run-aps.csv --rate-hz 1 --sigma-m 0.06 --seed 7\n"
      "  odotune tune --track run-aps.csv --model alpha\n"
      "Existing aps_x/aps_y columns are replaced.");
  sub->add_option("track", args->track, "input track")->required();
  sub->add_option("-o,--output", args->output, "output track")->required();
  sub->add_option("--rate-hz", args->options.rate_hz, "fix frequency [Hz]");
  sub->add_option("--sigma-m", args->options.sigma_m, "noise σ per axis [m]");
  sub->add_option("--seed", args->options.seed, "noise seed");
  sub->callback([args] {
    std::string why;
    if (!args->options.IsValid(&why)) throw Failure(why);
    const Track in = load_tracks({args->track}).front();
    Track out = [&] {
      try {
        return with_synthetic_fixes(in, args->options);
      } catch (const std::invalid_argument& e) {
        throw Failure(e.what());
      }
    }();
    try {
      write_track(out, args->output);
    } catch (const std::exception& e) {
      throw Failure(e.what());
    }
    fmt::print("{}: {}\n", args->output, *out.meta().get("fixes.synthetic"));
  });
}

}  // namespace odotune::cli
