// What every solver run does first and last (internal to tuner/): time the
// run, check the options and the problem's box, and turn the ending into a
// Summary's termination. Shared so that PSO and the NLopt adapter report
// failures the same way.
#pragma once

#include <chrono>
#include <exception>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <utility>

#include <odotune/core/stopwatch.h>
#include <odotune/tuner/problem.h>
#include <odotune/tuner/summary.h>

namespace odotune::tuner::detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// A double as the messages print it.
inline std::string str(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

inline std::string what_of(std::exception_ptr e) {
  try {
    std::rethrow_exception(std::move(e));
  } catch (const std::exception& ex) {
    return ex.what();
  } catch (...) {
    return "unknown exception";
  }
}

class SolverRun {
 public:
  SolverRun() { summary.best_fitness = kInf; }

  // Validates `options` and fetches and validates the box into *box. On a
  // problem returns what is wrong, the message of a Termination::failure.
  template <typename Options>
  std::optional<std::string> start(const Options& options, ProblemRef problem, Bounds* box) {
    std::string why;
    if (!options.IsValid(&why)) return why;
    try {
      *box = problem.bounds();
    } catch (...) {
      return "bounds() threw: " + what_of(std::current_exception());
    }
    if (!box->IsValid(&why)) return why;
    return std::nullopt;
  }

  // Sets the termination, its message and the wall time, and returns the summary.
  Summary finish(Termination termination, std::string message = {}) {
    summary.termination = termination;
    summary.message = std::move(message);
    summary.seconds = core::seconds_since(t0_);
    return summary;
  }

  Summary summary;

 private:
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
};

}  // namespace odotune::tuner::detail
