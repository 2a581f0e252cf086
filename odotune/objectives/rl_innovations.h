// Tuning statistics of a filter's innovations, the field's criteria for
// tuning without ground truth (docs/husky.md, "Methods tried"):
//   innovation_nll  the negative log-likelihood of the fused fixes'
//                   innovations, mean over fixes of νᵀS⁻¹ν + ln det S: the
//                   prediction-error decomposition of maximum likelihood;
//   nis_cost        |ln(mean NIS / 2)| with NIS = νᵀS⁻¹ν: Chen et al., "Weak in
//                   the NEES?: Auto-tuning Kalman Filters with Bayesian
//                   Optimization" (FUSION 2018), their J_NIS on one run;
//   whiteness_cost  Σ_{j=1..L} ρ_j² + ln(mean NIS / 2)²: the innovations'
//                   autocorrelations at lags 1..L, which an optimal filter's
//                   are zero (Mehra 1970), and the lag-0 consistency: what the
//                   autocovariance least squares of Odelson, Rajamani and
//                   Rawlings (Automatica 2006) fits Q and R to, for filters
//                   that are not linear and time-invariant;
//   heldout_nll     mean over held-out fixes of eᵀC⁻¹e + ln det C, e the
//                   prediction error, C the predicted covariance plus the
//                   fix's: fitness mode 9's idea on this filter.
// Non-finite (NaN) without innovations or with a covariance that is not
// positive definite.
#pragma once

#include <span>

#include <odotune/rlnode/replay.h>

namespace odotune::objectives {

double innovation_nll(std::span<const rlnode::Innovation> v);
double nis_cost(std::span<const rlnode::Innovation> v);
double whiteness_cost(std::span<const rlnode::Innovation> v, int lags = 10);
double heldout_nll(std::span<const rlnode::ReplayOutput> outputs);

}  // namespace odotune::objectives
