#include "cli/commands.h"
#include "cli/failure.h"

namespace odotune::cli {

// Not built yet: the command exists so that --help lists it, and says so plainly.
void register_tune(CLI::App& app) {
  auto* sub = app.add_subcommand("tune", "(not built yet)");
  sub->allow_extras();
  sub->callback([] { throw Failure("'tune' is not built yet", 2); });
}

}  // namespace odotune::cli
