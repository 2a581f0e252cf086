#include <odotune/tuner/nlopt_solver.h>

// The C API is used on purpose: the adapter needs full control over what
// crosses NLopt's C frames (its callback is noexcept and catches everything)
// and over force-stop; nlopt.hpp would rethrow its own exception types.
#include <nlopt.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <climits>
#include <cmath>
#include <exception>
#include <limits>
#include <memory>
#include <sstream>
#include <utility>

#include <odotune/core/why.h>
#include <odotune/tuner/solver_run.h>

namespace odotune::tuner {
namespace {

using detail::kInf;
using detail::str;
using detail::what_of;

struct AlgorithmInfo {
  const char* name;
  nlopt_algorithm algorithm;
  bool global;
};

// The supported algorithms; order = nlopt_algorithm_names() order.
constexpr AlgorithmInfo kAlgorithms[] = {
    {"DIRECT", NLOPT_GN_DIRECT, true},
    {"DIRECT_L", NLOPT_GN_DIRECT_L, true},
    {"DIRECT_L_RAND", NLOPT_GN_DIRECT_L_RAND, true},
    {"CRS2_LM", NLOPT_GN_CRS2_LM, true},
    {"ISRES", NLOPT_GN_ISRES, true},
    {"ESCH", NLOPT_GN_ESCH, true},
    {"MLSL_LDS", NLOPT_G_MLSL_LDS, true},
    {"BOBYQA", NLOPT_LN_BOBYQA, false},
    {"SBPLX", NLOPT_LN_SBPLX, false},
    {"NELDERMEAD", NLOPT_LN_NELDERMEAD, false},
    {"COBYLA", NLOPT_LN_COBYLA, false},
    {"PRAXIS", NLOPT_LN_PRAXIS, false},
};
// Local optimiser used inside MLSL_LDS.
constexpr nlopt_algorithm kMlslLocal = NLOPT_LN_BOBYQA;

std::string upper(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

const AlgorithmInfo* find_algorithm(std::string_view name) {
  const std::string key = upper(name);
  for (const AlgorithmInfo& a : kAlgorithms)
    if (key == a.name) return &a;
  return nullptr;
}

std::string result_name(nlopt_result r) {
  const char* s = nlopt_result_to_string(r);
  return s != nullptr ? s : "result " + std::to_string(static_cast<int>(r));
}

struct OptDeleter {
  void operator()(nlopt_opt o) const { nlopt_destroy(o); }
};
using OptPtr = std::unique_ptr<std::remove_pointer_t<nlopt_opt>, OptDeleter>;

// State shared with the NLopt callback (one run, calling thread only).
struct Run {
  Run(ProblemRef p, const NloptOptions& o, nlopt_opt handle) : problem(p), options(o), opt(handle) {}
  ProblemRef problem;
  const NloptOptions& options;
  nlopt_opt opt;
  long evaluations = 0;
  double best_f = kInf;
  std::vector<double> best_x;
  std::vector<LogRecord> log;
  std::string failure;      // non-empty: the fitness/progress threw
  bool stopped = false;     // the caller's stop flag was seen
  bool budget_hit = false;  // NLopt asked for more than max_evaluations
  long last_percent = -1;   // last percentage passed to progress

  bool halted() const { return !failure.empty() || stopped || budget_hit; }
};

// NLopt objective. noexcept: nothing may unwind through NLopt's C frames.
double objective(unsigned n, const double* x, double* grad, void* data) noexcept {
  (void)grad;  // derivative-free algorithms only: grad is always null
  Run& run = *static_cast<Run*>(data);
  // Once a stop was forced, some algorithms (e.g. CRS2_LM while building its
  // initial population) still ask for points: refuse them all.
  if (run.halted()) return kInf;
  if (run.options.stop != nullptr && run.options.stop->load()) {
    run.stopped = true;
    nlopt_force_stop(run.opt);
    return kInf;
  }
  if (run.evaluations >= run.options.max_evaluations) {
    run.budget_hit = true;
    nlopt_force_stop(run.opt);
    return kInf;
  }
  ++run.evaluations;  // an evaluation that throws still counts
  double f = kInf;
  try {
    f = run.problem.fitness(std::span<const double>(x, n));
  } catch (...) {
    run.failure = what_of(std::current_exception());
    nlopt_force_stop(run.opt);
    return kInf;
  }
  if (std::isfinite(f) && f < run.best_f) {
    run.best_f = f;
    run.best_x.assign(x, x + n);
    run.log.push_back({static_cast<int>(std::min<long>(run.evaluations, INT_MAX)), run.evaluations, f});
  }
  if (run.options.progress) {
    const long percent = run.evaluations * 100 / run.options.max_evaluations;
    if (percent != run.last_percent) {
      run.last_percent = percent;
      try {
        run.options.progress(run.evaluations, run.options.max_evaluations);
      } catch (...) {
        run.failure = "progress callback threw: " + what_of(std::current_exception());
        nlopt_force_stop(run.opt);
      }
    }
  }
  // NLopt gets +inf for non-finite values (NaN would corrupt comparisons).
  return std::isfinite(f) ? f : kInf;  // NOLINT(bugprone-narrowing-conversions): false positive on +inf
}

}  // namespace

const std::vector<std::string>& nlopt_algorithm_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const AlgorithmInfo& a : kAlgorithms) v.emplace_back(a.name);
    return v;
  }();
  return names;
}

bool nlopt_is_global(std::string_view name) {
  const AlgorithmInfo* a = find_algorithm(name);
  return a != nullptr && a->global;
}

bool NloptOptions::IsValid(std::string* why) const {
  if (find_algorithm(algorithm) == nullptr) {
    std::string list;
    for (const std::string& n : nlopt_algorithm_names()) list += (list.empty() ? "" : ", ") + n;
    return core::invalid(why, "nlopt: unknown algorithm '" + algorithm + "'; expected one of: " + list);
  }
  if (max_evaluations < 1)
    return core::invalid(why,
                         "nlopt: max_evaluations = " + std::to_string(max_evaluations) + ", expected >= 1");
  if (!(std::isfinite(xtol_rel) && xtol_rel >= 0))
    return core::invalid(why, "nlopt: xtol_rel = " + str(xtol_rel) + ", expected a finite value >= 0");
  if (x0) {
    if (x0->empty()) return core::invalid(why, "nlopt: x0 is empty, expected one value per dimension");
    for (std::size_t i = 0; i < x0->size(); ++i)
      if (!std::isfinite((*x0)[i]))
        return core::invalid(why, "nlopt: x0[" + std::to_string(i) + "] = " + str((*x0)[i]) +
                                      ", expected a finite value");
  }
  return true;
}

Summary nlopt_minimize(ProblemRef problem, const NloptOptions& options) {
  detail::SolverRun solver_run;
  Summary& summary = solver_run.summary;
  auto finish = [&solver_run](Termination t, std::string message = {}) {
    return solver_run.finish(t, std::move(message));
  };
  Bounds box;
  if (auto failure = solver_run.start(options, problem, &box)) return finish(Termination::failure, *failure);
  std::string why;
  const std::size_t dim = box.dimension();

  std::vector<double> x(dim);
  if (options.x0) {
    if (options.x0->size() != dim)
      return finish(Termination::failure, "nlopt: x0 has " + std::to_string(options.x0->size()) +
                                              " entries, expected " + std::to_string(dim) +
                                              " (the box dimension)");
    if (!box.Contains(*options.x0))
      return finish(Termination::failure, "nlopt: x0 lies outside the box, expected lower <= x0 <= upper");
    x = *options.x0;
  } else {
    for (std::size_t d = 0; d < dim; ++d) x[d] = 0.5 * (box.lower[d] + box.upper[d]);
  }

  const AlgorithmInfo& info = *find_algorithm(options.algorithm);
  const std::vector<double> start = x;
  const unsigned n = static_cast<unsigned>(dim);
  OptPtr opt(nlopt_create(info.algorithm, n));
  if (!opt) return finish(Termination::failure, "nlopt: could not create " + std::string(info.name));

  Run run(problem, options, opt.get());
  auto check = [&](nlopt_result r, const char* what) {
    if (r >= 0) return true;
    const char* msg = nlopt_get_errmsg(opt.get());
    why = "nlopt: " + std::string(what) + ": " + result_name(r) +
          (msg != nullptr ? std::string(" (") + msg + ")" : "");
    return false;
  };
  if (!check(nlopt_set_lower_bounds(opt.get(), box.lower.data()), "set_lower_bounds") ||
      !check(nlopt_set_upper_bounds(opt.get(), box.upper.data()), "set_upper_bounds") ||
      !check(nlopt_set_min_objective(opt.get(), objective, &run), "set_min_objective") ||
      !check(nlopt_set_maxeval(opt.get(), static_cast<int>(std::min<long>(options.max_evaluations, INT_MAX))),
             "set_maxeval") ||
      !check(nlopt_set_xtol_rel(opt.get(), info.global ? 0.0 : options.xtol_rel), "set_xtol_rel") ||
      (options.population > 0 && !check(nlopt_set_population(opt.get(), options.population), "set_population")))
    return finish(Termination::failure, why);
  if (info.algorithm == NLOPT_G_MLSL_LDS) {
    OptPtr local(nlopt_create(kMlslLocal, n));
    if (!local) return finish(Termination::failure, "nlopt: could not create the MLSL local optimizer");
    if (!check(nlopt_set_xtol_rel(local.get(), options.xtol_rel), "local set_xtol_rel") ||
        !check(nlopt_set_local_optimizer(opt.get(), local.get()), "set_local_optimizer"))
      return finish(Termination::failure, why);
  }

  // Fold the 64-bit seed: NLopt's generator uses only the low 32 bits.
  nlopt_srand(static_cast<unsigned long>((options.seed ^ (options.seed >> 32)) & 0xffffffffULL));
  double f_opt = kInf;
  const nlopt_result result = nlopt_optimize(opt.get(), x.data(), &f_opt);

  summary.evaluations = run.evaluations;
  summary.iterations = static_cast<int>(std::min<long>(run.evaluations, INT_MAX));
  summary.best_fitness = run.best_f;
  summary.best_x = run.best_x.empty() ? start : run.best_x;
  summary.log = std::move(run.log);
  if (!run.failure.empty()) return finish(Termination::failure, run.failure);
  if (run.stopped) return finish(Termination::stopped);
  if (run.budget_hit || result == NLOPT_MAXEVAL_REACHED) return finish(Termination::max_evaluations);
  if (result == NLOPT_ROUNDOFF_LIMITED || result > 0)
    return finish(Termination::solver_criterion, "nlopt: " + result_name(result));
  const char* msg = nlopt_get_errmsg(opt.get());
  return finish(Termination::failure,
                "nlopt: " + result_name(result) + (msg != nullptr ? std::string(" (") + msg + ")" : ""));
}

}  // namespace odotune::tuner
