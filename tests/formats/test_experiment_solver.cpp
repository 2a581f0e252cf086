// An experiment's solver (odotune/formats/experiment_yaml.h) is parsed when the
// file is read: the grid's cells get a tuner::SolverChoice, never the text,
// and a solver that is not one is refused with the file and line.
#include <odotune/formats/experiment_yaml.h>

#include <string>

#include <gtest/gtest.h>

#include <odotune/core/failure.h>

namespace odotune::formats {
namespace {

std::string experiment_with_solver(const std::string& solver_line) {
  return "format: odotune-experiment/1\nmodels: [rq]\ntracks: [" + std::string(ODOTUNE_SOURCE_DIR) +
         "/data/tracks/track1.csv]\nmodes: [7]\nseeds: [1]\n" + solver_line;
}

TEST(ExperimentSolver, IsParsedWhenTheFileIsRead) {
  const Experiment pso = parse_experiment(experiment_with_solver(""), "e.yaml");
  EXPECT_EQ(pso.solver.kind, tuner::SolverChoice::Kind::pso);
  const Experiment nlopt = parse_experiment(experiment_with_solver("solver: nlopt:SBPLX\n"), "e.yaml");
  EXPECT_EQ(nlopt.solver.kind, tuner::SolverChoice::Kind::nlopt);
  EXPECT_EQ(nlopt.solver.nlopt_algorithm, "SBPLX");
  EXPECT_EQ(nlopt.solver.name(), "nlopt:SBPLX");  // what the store records, as written
}

TEST(ExperimentSolver, AnUnknownSolverNamesTheFileAndLine) {
  for (const std::string bad : {"annealing", "nlopt:LN_BOGUS"}) {
    try {
      parse_experiment(experiment_with_solver("solver: " + bad + "\n"), "e.yaml");
      ADD_FAILURE() << bad << " was accepted";
    } catch (const core::Failure& f) {
      const std::string what = f.what();
      EXPECT_EQ(what.rfind("e.yaml:6:", 0), 0u) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
      EXPECT_NE(what.find(bad == "annealing" ? "expected pso or nlopt:NAME" : "LN_BOGUS"), std::string::npos)
          << what;
    }
  }
}

}  // namespace
}  // namespace odotune::formats
