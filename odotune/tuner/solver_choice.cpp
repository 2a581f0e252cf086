#include <odotune/tuner/solver_choice.h>

#include <odotune/tuner/nlopt_solver.h>

namespace odotune::tuner {

std::optional<SolverChoice> SolverChoice::parse(std::string_view text, std::string* why) {
  if (text == "pso") return SolverChoice{};
  constexpr std::string_view kNlopt = "nlopt:";
  if (text.substr(0, kNlopt.size()) != kNlopt) {
    if (why) *why = "solver '" + std::string(text) + "': expected pso or nlopt:NAME";
    return std::nullopt;
  }
  NloptOptions o;
  o.algorithm = std::string(text.substr(kNlopt.size()));
  if (!o.IsValid(why)) return std::nullopt;
  return SolverChoice{Kind::nlopt, o.algorithm};
}

std::string SolverChoice::name() const {
  switch (kind) {
    case Kind::pso: return "pso";
    case Kind::nlopt: return "nlopt:" + nlopt_algorithm;
  }
  return "pso";  // not reached: the switch is exhaustive (-Wswitch)
}

}  // namespace odotune::tuner
