// Adapter from a ProblemRef to NLopt (S. G. Johnson, "The NLopt nonlinear-
// optimization package", https://github.com/stevengj/nlopt), derivative-free
// algorithms only. Bounds are always the problem's finite box.
//
// Algorithms (names without NLopt's GN_/LN_ prefix, case-insensitive):
//   global: DIRECT, DIRECT_L, DIRECT_L_RAND, CRS2_LM, ISRES, ESCH, MLSL_LDS
//           (MLSL_LDS = NLopt's G_MLSL_LDS with LN_BOBYQA as local optimizer,
//           which uses the same xtol_rel; its bookkeeping costs O(evaluations²)
//           time, ~0.1–0.4 s at 7550 evaluations, negligible for costly fitness)
//   local:  BOBYQA, SBPLX, NELDERMEAD, COBYLA, PRAXIS
//   Seed-dependent: DIRECT_L_RAND, CRS2_LM, ISRES, ESCH, and PRAXIS (random
//   steps only in some situations). MLSL_LDS draws its start points from a
//   Sobol sequence, so the seed has little or no effect on it; the others are
//   deterministic.
//
// Start point: x0 if given, else the box centre. Local algorithms start from
// it; NLopt's stochastic global algorithms may use it as one of their initial
// points (CRS2_LM does); the DIRECT family ignores it.
//
// Budget: NLopt's maxeval is set to max_evaluations (the same kind of budget
// as PsoOptions::evaluation_budget()). Some NLopt algorithms check maxeval
// only between batches and ask for more points (seen with NLopt 2.7.1:
// CRS2_LM when the budget is below its initial population, PRAXIS with small
// budgets). The adapter refuses every call beyond the budget (it returns +inf
// without calling the fitness and forces NLopt to stop), so
// Summary::evaluations <= max_evaluations always, with no overshoot.
// Likewise, once a run is stopped or failed, every further point NLopt asks
// for (CRS2_LM, for one, finishes its initial population regardless) is
// refused without calling the fitness.
//
// Evaluations run sequentially on the calling thread (NLopt is serial); the
// fitness may itself use OpenMP.
//
// Randomness: nlopt_srand() is called with the (32-bit folded) seed on the
// calling thread right before each run. Debian's NLopt 2.7.1 keeps its
// Mersenne-Twister state and its "seeded" flag thread-local (checked in the
// installed libnlopt_cxx.so: nlopt_srand and nlopt_init_genrand reach their
// state through __tls_get_addr). Consequence: concurrent nlopt_minimize runs
// on different threads have independent generators and each is reproducible
// from its seed. Two runs on the same thread interleaved (e.g. a fitness that
// itself calls nlopt_minimize) would share one stream and are not
// reproducible. An NLopt built without thread-local storage would make
// concurrent runs race on one global generator — run them sequentially there.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <odotune/tuner/problem.h>
#include <odotune/tuner/summary.h>

namespace odotune::tuner {

struct NloptOptions {
  std::string algorithm = "CRS2_LM";      // one of nlopt_algorithm_names(), any case
  long max_evaluations = 7550;            // >= 1; default = PsoOptions{}.evaluation_budget()
  std::uint64_t seed = 0;                 // explicit seed (NLopt uses its low 32 bits
                                          // after folding: seed ^ (seed >> 32))
  double xtol_rel = 1e-6;                 // NLopt relative x tolerance, >= 0 (0 = off).
                                          // Used by the local algorithms and by MLSL_LDS's
                                          // local searches only: global algorithms run
                                          // until max_evaluations (their own x-tolerance
                                          // tests end e.g. CRS2_LM inside a local basin)
  unsigned population = 0;                // CRS2_LM, ISRES, ESCH, MLSL_LDS: population /
                                          // points per iteration; 0 = NLopt's default
  std::optional<std::vector<double>> x0;  // start point (finite, inside the box)

  // Optional. Called from the calling thread (inside NLopt's callback, never
  // from a parallel region) whenever the completed percentage of the budget
  // grows, with (evaluations done, max_evaluations).
  std::function<void(long done, long total)> progress;
  // Optional. Polled before every evaluation; when it reads true the run
  // ends with Termination::stopped.
  const std::atomic<bool>* stop = nullptr;

  // True if usable; otherwise false and *why (if given) says what is wrong,
  // e.g. "nlopt: unknown algorithm 'FOO'; expected one of: DIRECT, ...".
  // x0's size and position can only be checked against the problem's box:
  // nlopt_minimize reports those as a failure.
  bool IsValid(std::string* why) const;
};

// Canonical (upper-case) names of the supported algorithms.
const std::vector<std::string>& nlopt_algorithm_names();
// True for the global algorithms above; false for local and unknown names.
bool nlopt_is_global(std::string_view name);

// Minimises problem.fitness over problem.bounds() with NLopt.
// Summary: best_x/best_fitness are the best evaluated point (tracked by the
// adapter, not NLopt's return); log has a record at every strict improvement
// (iteration = 1-based evaluation index); iterations = evaluations.
// termination: max_evaluations (NLopt's MAXEVAL_REACHED or the adapter's
// cap), stopped, solver_criterion with message "nlopt: <CODE>" for NLopt's
// other endings (SUCCESS, STOPVAL_REACHED, FTOL_REACHED, XTOL_REACHED,
// MAXTIME_REACHED, ROUNDOFF_LIMITED — the last still returns a usable point),
// or failure (message: what) for invalid options/bounds/x0, an NLopt error,
// or an exception thrown by the fitness or progress callback. Never throws for
// those; exceptions never pass through NLopt's C code.
Summary nlopt_minimize(ProblemRef problem, const NloptOptions& options);

}  // namespace odotune::tuner
