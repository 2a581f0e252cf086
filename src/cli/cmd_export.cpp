// odotune export (being written; says so plainly until it is).
#include "cli/commands.h"
#include "cli/failure.h"

namespace odotune::cli {

void register_export(CLI::App& app) {
  auto* sub = app.add_subcommand("export", "(not built yet)");
  sub->callback([] { throw Failure("odotune export is not built yet"); });
}

}  // namespace odotune::cli
