#include <exception>
#include <iostream>

#include <odotune/cli/commands.h>
#include <odotune/core/failure.h>

namespace odotune::cli {

int run(int argc, char** argv) {
  CLI::App app{"odotune: tune and calibrate the localisation filters of wheeled robots "
               "from recorded tracks"};
  app.set_version_flag("--version", std::string("odotune ") + ODOTUNE_VERSION);
  app.require_subcommand(1);
  // One line per error (CLI11's default adds a second, "Run with --help …").
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return std::string("odotune: ") + e.what() + " (see --help)\n";
  });
  register_simulate(app);
  register_import(app);
  register_tune(app);
  register_eval(app);
  register_demo(app);
  register_fixes(app);
  register_grid(app);
  register_report(app);
  register_export(app);
  register_diagnose(app);
  register_calibrate(app);
  register_study(app);
  register_learn(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const core::Failure& e) {
    std::cerr << "odotune: " << e.what() << "\n";
    return e.exit_code;
  } catch (const std::exception& e) {
    std::cerr << "odotune: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace odotune::cli
