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

// One window of a paired comparison of two models' predictions against a
// reference: each model's SSE over the window's samples, normalised by the
// reference sigmas (and weights); their predictions' normalised squared
// difference, sum |delta|^2; and the error components summed (samples times
// 2, or 3 with heading).
struct WindowPair {
  double sse_ref = 0.0, sse_alt = 0.0;
  double delta2 = 0.0;
  double components = 0.0;
};

// The paired comparison of `alt` against `ref` over their windows.
struct PairedComparison {
  double rel = 0.0, gain = 0.0;   // (ref - alt)/ref and ref - alt of the pooled scores (set by the caller)
  int changed = 0, improved = 0;  // informative windows, and those alt improved
  double p_rank = 1.0;            // Wilcoxon signed-rank, one-sided
  double p_t = 0.0;               // min of the t-tests on z and l (NaN with < 3 windows)
  double p_param = 0.0;           // Stouffer (NaN with < 3 windows unless every one improved)
  bool significant = false;
};

// A window is informative when alt moves its normalised predictions by
// delta2 >= 4 L (below, the window's gain cannot stand out of the reference
// noise; L = correlated: how many consecutive reference samples share their
// noise, 1 for a raw reference). Over informative windows: d_w = SSE_ref(w) -
// SSE_alt(w), z_w = d_w / (2 s_w sqrt(L delta2)) with s_w^2 = max(1, alt's
// mean squared normalised error per component) (the white-noise law of d_w,
// inflated when the residual exceeds the noise), and l_w =
// ln(SSE_ref(w)/SSE_alt(w)). significant when any of
//  - the Wilcoxon signed-rank p on d < alpha (window signs and ranks; it
//    cannot go below 2^-n with n windows),
//  - the smaller of the t-test p's on z and on l < alpha/2 (consistent
//    standardised gains, or consistent relative gains when windows differ
//    in how much the effect shows; Bonferroni over the two),
//  - every informative window improved (at least 2) and Stouffer's p of z
//    < alpha (an effect acting in a few windows only), or, with at least 3
//    informative windows, Stouffer's p of the signed z of all of them but
//    the one with the largest z < alpha (a strong effect whose few
//    informative windows include a short one that it leaves slightly worse;
//    leaving the strongest window out keeps one window from carrying the
//    result).
// The three address different regimes; their union has a nominal level of
// at most 3 alpha.
PairedComparison paired_windows(const std::vector<WindowPair>& windows, double correlated, double alpha);

// Regularised incomplete beta function I_x(a, b), a, b > 0, x in [0, 1]
// (continued fraction; used for the t distribution).
double incomplete_beta(double x, double a, double b);

}  // namespace odotune::diagnose
