#include <odotune/tuner/summary.h>

namespace odotune::tuner {

const char* to_string(Termination t) {
  switch (t) {
    case Termination::max_iterations: return "max_iterations";
    case Termination::max_evaluations: return "max_evaluations";
    case Termination::stopped: return "stopped";
    case Termination::solver_criterion: return "solver_criterion";
    case Termination::failure: return "failure";
  }
  return "failure";  // not reached: the switch is exhaustive (-Wswitch)
}

std::string Summary::termination_text() const {
  switch (termination) {
    case Termination::solver_criterion: return message;
    case Termination::failure: return "failure: " + message;
    case Termination::max_iterations:
    case Termination::max_evaluations:
    case Termination::stopped: break;
  }
  return to_string(termination);
}

}  // namespace odotune::tuner
