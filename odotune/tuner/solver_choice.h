// Which solver a tune runs: PSO, or an NLopt algorithm by name. Parsed once
// from its text form ("pso", "nlopt:NAME") where a request comes in; the
// text form is what outputs, JSON and stores print.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace odotune::tuner {

struct SolverChoice {
  enum class Kind { pso, nlopt };
  Kind kind = Kind::pso;
  std::string nlopt_algorithm;  // kind == nlopt: one of nlopt_algorithm_names(), any case

  // "pso" or "nlopt:NAME" (NAME checked as NloptOptions::IsValid checks it);
  // nullopt and *why (one line) for anything else.
  static std::optional<SolverChoice> parse(std::string_view text, std::string* why);
  // "pso" or "nlopt:NAME".
  std::string name() const;

  bool operator==(const SolverChoice&) const = default;
};

}  // namespace odotune::tuner
