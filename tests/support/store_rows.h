// A results store's rows as text, keyed by run, for comparing two stores
// bit-exactly: every field but the wall time (parameter ranges included),
// doubles in hex (%a).
#pragma once

#include <filesystem>
#include <map>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <odotune/results/store.h>

namespace odotune::testing_support {

inline std::map<std::string, std::string> store_rows(const std::filesystem::path& store) {
  std::map<std::string, std::string> out;
  for (const auto& r : results::Store(store).runs()) {
    std::string v = fmt::format("{:a} {:a} {:a} {:a} {:a} {:a} {:a} {} {} {}", r.best_fitness,
                                r.baseline.rmse_m, r.baseline.mae_m, r.baseline.maxe_m, r.tuned.rmse_m,
                                r.tuned.mae_m, r.tuned.maxe_m, r.evaluations, r.diverged, r.termination);
    for (std::size_t i = 0; i < r.params.size(); ++i)
      v += fmt::format(" {}={:a}", i < r.param_names.size() ? r.param_names[i] : "?", r.params[i]);
    for (const auto& g : r.param_ranges) v += fmt::format(" [{:a},{:a},{}]", g.lo, g.hi, g.determined);
    for (const auto& c : r.convergence) v += fmt::format(" {}:{:a}", c.evaluations, c.best_fitness);
    EXPECT_TRUE(out.emplace(results::run_key(r), v).second) << "duplicate run " << results::run_key(r);
  }
  return out;
}

}  // namespace odotune::testing_support
