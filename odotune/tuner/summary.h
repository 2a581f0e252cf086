// What a solver run reports (Ceres style): the best point found, how the run
// ended and a log of its progress. Logs are data for the caller to print or
// store; the tuner never prints.
#pragma once

#include <string>
#include <vector>

namespace odotune::tuner {

// One point of a run's convergence history.
struct LogRecord {
  int iteration = 0;        // PSO: swarm iteration (0 = initial swarm);
                            // NLopt: 1-based index of the evaluation that improved
  long evaluations = 0;     // fitness evaluations done so far
  double best_fitness = 0;  // best fitness so far (after this record's step)

  bool operator==(const LogRecord&) const = default;
};

// Why a run ended (Ceres' TerminationType is the model).
enum class Termination {
  max_iterations,    // PSO ran all its iterations
  max_evaluations,   // the evaluation budget is used up (NLopt)
  stopped,           // the caller's stop flag was raised
  solver_criterion,  // the solver's own criterion (message: e.g. "nlopt: XTOL_REACHED")
  failure,           // invalid input, or the fitness (or progress callback) threw (message: what)
};

// "max_iterations", "max_evaluations", "stopped", "solver_criterion", "failure".
const char* to_string(Termination t);

struct Summary {
  std::vector<double> best_x;  // best point evaluated; if no finite fitness was
                               // seen, the start point (PSO: particle 0's first
                               // position; NLopt: x0 or the box centre); empty
                               // if the run failed before any value was recorded
  double best_fitness = 0;     // its fitness; +infinity if no finite value was seen
  long evaluations = 0;        // fitness calls made
  int iterations = 0;          // PSO: completed swarm iterations after the initial
                               // one; NLopt: equal to evaluations (capped at INT_MAX)
  Termination termination = Termination::failure;
  std::string message;         // solver_criterion and failure: what (see Termination)
  double seconds = 0;          // wall-clock duration of the run [s]
  std::vector<LogRecord> log;  // convergence history, in order

  bool ok() const { return termination != Termination::failure; }
  // The end as one line, as outputs and stores print it: the termination's
  // name; the message for solver_criterion ("nlopt: XTOL_REACHED"); "failure:
  // <message>" for failure.
  std::string termination_text() const;
};

}  // namespace odotune::tuner
