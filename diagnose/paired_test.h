// One-sided tests that paired differences are positive, for the model
// selection of the diagnosis (select.h): per held-out window, how much a
// candidate model lowers the error. No I/O; deterministic.
#pragma once

#include <vector>

namespace odotune::diagnose {

// Upper tail of the standard normal distribution, P(Z > z).
double normal_upper_tail(double z);

// One-sided p of the Wilcoxon signed-rank test that d is centred above 0.
// Zeros must be removed by the caller; ties get average ranks. Exact (the
// distribution of the rank sum enumerated, ties included) up to 60 values,
// normal approximation with continuity correction above. 1 for no value.
// With n values the smallest p is 2^-n.
double wilcoxon_greater(const std::vector<double>& d);

// One-sided p of the one-sample Student t-test that the mean of v is > 0
// (NaN for fewer than 3 values; 0 or 1 when all values are equal).
double t_test_greater(const std::vector<double>& v);

// One-sided Stouffer p that the z-scores z (independent, standard normal
// under the null) are centred above 0: normal_upper_tail(sum z / sqrt(n)).
// stouffer_greater: all of them (NaN for none). stouffer_greater_but_strongest:
// all but the largest, so that no single value carries the result (NaN for
// fewer than 3 values).
double stouffer_greater(const std::vector<double>& z);
double stouffer_greater_but_strongest(const std::vector<double>& z);

// Regularised incomplete beta function I_x(a, b), a, b > 0, x in [0, 1]
// (continued fraction; used for the t distribution).
double incomplete_beta(double x, double a, double b);

}  // namespace odotune::diagnose
