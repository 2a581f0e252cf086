#include "cli/commands.h"
#include "cli/failure.h"

namespace odotune::cli {

// Not built yet: the command exists so that --help lists it, and says so plainly.
void register_demo(CLI::App& app) {
  auto* sub = app.add_subcommand("demo", "(not built yet)");
  sub->allow_extras();
  sub->callback([] { throw Failure("'demo' is not built yet", 2); });
}

}  // namespace odotune::cli
