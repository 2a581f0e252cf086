// odotune report (being written; says so plainly until it is).
#include "cli/commands.h"
#include "cli/failure.h"

namespace odotune::cli {

void register_report(CLI::App& app) {
  auto* sub = app.add_subcommand("report", "(not built yet)");
  sub->callback([] { throw Failure("odotune report is not built yet"); });
}

}  // namespace odotune::cli
