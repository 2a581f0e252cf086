#include <odotune/filters/pf_calibrator.h>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <odotune/core/counter_rng.h>
#include <odotune/core/enum_names.h>
#include <odotune/core/why.h>
#include <odotune/filters/pf_kernels.h>

namespace odotune::filters {

// Reference values subtracted from the particles before the weighted sums, so
// that the variances do not suffer cancellation (the previous estimate for
// the parameters, the measurement for the velocities).
struct PfCalibrator::Shifts {
  double r_right = 0.0, r_left = 0.0, base = 0.0, v = 0.0, w = 0.0;
};

namespace {

using pf_kernels::kGolden;

// Particles per reduction block: fixed, so that the partial sums (and hence
// the results) do not depend on the number of threads.
constexpr std::size_t kBlock = 1024;

// Weights below e^kMinLogWeight of the largest are set to 0 (negligible in any
// sum of doubles; keeps ρ² and ρ·d² clear of slow subnormal numbers).
constexpr double kMinLogWeight = -300.0;
// Evidence evolution: the smallest spread a parameter's walk scales with, as
// a fraction of its value (a cloud resampled onto one value must not freeze).
constexpr double kMinRelativeSpread = 1e-6;

// Layout of one block's partial sums in block_sums_ (weights are
// exp(log ρ − max), the d* are differences from the Shifts).
enum SumIndex : std::size_t {
  kSumW,      // Σρ
  kSumW2,     // Σρ²
  kSumRr,     // Σρ·dR_R
  kSumRl,     // Σρ·dR_L
  kSumBase,   // Σρ·dD
  kSumV,      // Σρ·dV
  kSumWz,     // Σρ·dW
  kSumRr2,    // Σρ·dR_R²
  kSumRl2,    // Σρ·dR_L²
  kSumBase2,  // Σρ·dD²
  kSumCount
};

// counter_hash streams (ASCII tags), distinct from resampling.cpp's.
constexpr std::uint64_t kStreamInit = 0x5046494e4954ULL;         // "PFINIT"
constexpr std::uint64_t kStreamWalkRadii = 0x505757414c4b52ULL;  // "PWWALKR"
constexpr std::uint64_t kStreamWalkBase = 0x505757414c4b44ULL;   // "PWWALKD"
constexpr std::uint64_t kStreamVelocity = 0x5046564f44454cULL;   // "PFVODEL"

std::size_t block_count(std::size_t n) { return (n + kBlock - 1) / kBlock; }

std::string num(double x) {
  std::ostringstream os;
  os << x;
  return os.str();
}

bool check_range(const char* name, const PfCalibratorParams::Range& r, std::string* why) {
  if (std::isfinite(r.lo) && std::isfinite(r.hi) && r.lo > 0.0 && r.lo < r.hi) return true;
  return core::invalid(why, std::string(name) + " = [" + num(r.lo) + ", " + num(r.hi) +
                                "] must satisfy 0 < lo < hi (finite)");
}

bool check_non_negative(const char* name, double x, std::string* why) {
  if (std::isfinite(x) && x >= 0.0) return true;
  return core::invalid(why, std::string(name) + " = " + num(x) + " must be a finite number ≥ 0");
}

// Everything one block of the prediction/update needs (step 1–2).
struct PredictInputs {
  std::uint64_t key_radii, key_base, key_velocity;  // per-iteration stream keys
  double sigma_rr, sigma_rl, sigma_d;               // random-walk σ of R_R, R_L, D [m]
  double omega_l, omega_r;                          // [rad/s]
  double a_v, a_w;                                  // uniform half-widths
  double v_m, w_m;                                  // measurement
  double inv_v_var, inv_w_var;                      // 1/var
  double log_weight_shift;
};

// The two hot loops below are ODOTUNE_PF_HOT_LOOP functions (pf_kernels.h):
// compiled for x86-64-v4 (AVX-512, whose native 64-bit multiplies make the
// counter-based generator's SplitMix64 cheap: 0.17 → 0.09 ms per step at
// N = 8000, docs/benchmarks.md), AVX2 and baseline x86-64, with bit-identical
// results. They are functions of their own because GCC does not vectorise them
// once inlined into an OpenMP region.
#if defined(__clang__)
// Clang may decline to vectorise a `#pragma omp simd` loop here and says so
// as a warning; the loop is correct either way.
#pragma clang diagnostic ignored "-Wpass-failed"
#endif

// Prediction and log-weight of particles [i0, i1); returns their largest
// log-weight (−∞ when all are −∞). NaN log-weights become −∞ (weight 0).
template <bool kPerturb>
ODOTUNE_PF_HOT_LOOP double predict_block(const PredictInputs in, double* __restrict r_right,
                                         double* __restrict r_left, double* __restrict base,
                                         double* __restrict v, double* __restrict w,
                                         double* __restrict log_weight, std::size_t i0, std::size_t i1) {
  double block_max = -std::numeric_limits<double>::infinity();
#pragma omp simd reduction(max : block_max)
  for (std::size_t i = i0; i < i1; ++i) {
    const std::uint64_t n = static_cast<std::uint64_t>(i) * kGolden;
    const pf_kernels::NormalPair z_radii = pf_kernels::normal_pair_from_bits(
        core::splitmix64_mix(in.key_radii + n));
    const pf_kernels::NormalPair z_base = pf_kernels::normal_pair_from_bits(
        core::splitmix64_mix(in.key_base + n));
    const double rr = r_right[i] + in.sigma_rr * z_radii.first;
    const double rl = r_left[i] + in.sigma_rl * z_radii.second;
    const double d = base[i] + in.sigma_d * z_base.first;
    double vi = 0.5 * (in.omega_r * rr + in.omega_l * rl);
    double wi = (in.omega_r * rr - in.omega_l * rl) / d;
    if constexpr (kPerturb) {
      // The paper's uniform perturbation of V and W (no draw when it is
      // integrated out of the weight instead, the evidence evolution).
      const std::uint64_t u_bits = core::splitmix64_mix(in.key_velocity + n);
      vi += in.a_v * (2.0 * pf_kernels::uniform_high32(u_bits) - 1.0);
      wi += in.a_w * (2.0 * pf_kernels::uniform_low32(u_bits) - 1.0);
    }
    const double dv = in.v_m - vi;
    const double dw = in.w_m - wi;
    double lw = log_weight[i] - in.log_weight_shift - 0.5 * (dv * dv * in.inv_v_var + dw * dw * in.inv_w_var);
    lw = pf_kernels::select(lw == lw, lw, -std::numeric_limits<double>::infinity());
    r_right[i] = rr;
    r_left[i] = rl;
    base[i] = d;
    v[i] = vi;
    w[i] = wi;
    log_weight[i] = lw;
    block_max = pf_kernels::select(lw > block_max, lw, block_max);
  }
  return block_max;
}

// Everything one block of the weighting and moments needs (steps 3–4).
struct EstimateInputs {
  double max_log_weight;
  double min_log_weight;  // kMinLogWeight (run-time: see ExpClamp)
  pf_kernels::ExpClamp clamp;
  double c_rr, c_rl, c_d, c_v, c_w;  // Shifts
};

// Weights ρ = exp(log ρ − max) of particles [i0, i1) into `weight`, and their
// partial sums (layout SumIndex) into `out`. Weights below e^kMinLogWeight of
// the largest are set to exactly 0 by sending their argument to −∞.
//
// The sums are kept in kLanes explicit lanes (particle i0 + j in lane
// j mod kLanes) and the lanes added in order at the end: the summation order
// is fixed by the source, not by the vector width the compiler picks, so the
// SSE2 and AVX2 versions give identical results.
constexpr std::size_t kLanes = 8;

inline void weigh_one(const EstimateInputs& in, std::size_t i, std::size_t lane,
                      const double* __restrict r_right, const double* __restrict r_left,
                      const double* __restrict base, const double* __restrict v, const double* __restrict w,
                      const double* __restrict log_weight, double* __restrict weight,
                      double (&acc)[kSumCount][kLanes]) {
  const double x = log_weight[i] - in.max_log_weight;
  const double rho = pf_kernels::fast_exp_nonpositive(
      pf_kernels::select(x < in.min_log_weight, in.clamp.floor, x), in.clamp);
  weight[i] = rho;
  const double drr = r_right[i] - in.c_rr;
  const double drl = r_left[i] - in.c_rl;
  const double dd = base[i] - in.c_d;
  acc[kSumW][lane] += rho;
  acc[kSumW2][lane] += rho * rho;
  acc[kSumRr][lane] += rho * drr;
  acc[kSumRl][lane] += rho * drl;
  acc[kSumBase][lane] += rho * dd;
  acc[kSumV][lane] += rho * (v[i] - in.c_v);
  acc[kSumWz][lane] += rho * (w[i] - in.c_w);
  acc[kSumRr2][lane] += rho * drr * drr;
  acc[kSumRl2][lane] += rho * drl * drl;
  acc[kSumBase2][lane] += rho * dd * dd;
}

ODOTUNE_PF_HOT_LOOP void estimate_block(const EstimateInputs in, const double* __restrict r_right,
                                        const double* __restrict r_left, const double* __restrict base,
                                        const double* __restrict v, const double* __restrict w,
                                        const double* __restrict log_weight, double* __restrict weight,
                                        std::size_t i0, std::size_t i1, double* __restrict out) {
  double acc[kSumCount][kLanes] = {};
  const std::size_t full = i0 + (i1 - i0) / kLanes * kLanes;
  for (std::size_t j = i0; j < full; j += kLanes) {
#pragma omp simd
    for (std::size_t lane = 0; lane < kLanes; ++lane)
      weigh_one(in, j + lane, lane, r_right, r_left, base, v, w, log_weight, weight, acc);
  }
  for (std::size_t i = full; i < i1; ++i)
    weigh_one(in, i, i - full, r_right, r_left, base, v, w, log_weight, weight, acc);
  for (std::size_t k = 0; k < kSumCount; ++k) {
    double sum = 0.0;
    for (std::size_t lane = 0; lane < kLanes; ++lane) sum += acc[k][lane];
    out[k] = sum;
  }
}

// Throws std::invalid_argument unless the sample's step, wheel rates,
// measurement and its variances are usable.
void check_sample(const CalibSample& s) {
  if (!(std::isfinite(s.dt_s) && s.dt_s >= 0.0))
    throw std::invalid_argument("CalibSample: dt_s = " + num(s.dt_s) + " must be finite and ≥ 0");
  if (!std::isfinite(s.omega_l_rad_s) || !std::isfinite(s.omega_r_rad_s))
    throw std::invalid_argument("CalibSample: wheel rates must be finite");
  if (!std::isfinite(s.v_m_s) || !std::isfinite(s.w_rad_s))
    throw std::invalid_argument("CalibSample: the measurement (v_m_s, w_rad_s) must be finite");
  if (!(std::isfinite(s.v_var) && s.v_var > 0.0) || !(std::isfinite(s.w_var) && s.w_var > 0.0))
    throw std::invalid_argument("CalibSample: v_var = " + num(s.v_var) + ", w_var = " + num(s.w_var) +
                                " must be finite and > 0");
}

// §III: the random walk's σ, fixed, or eq. 11 for the adaptive variant
// (floored), from the measurement's departure from the last estimate.
double paper_sigma(const PfCalibratorParams& p, const CalibEstimate& estimate, const CalibSample& s,
                   long iteration) {
  double sd = p.random_walk_sigma_m;
  if (p.adaptive && iteration > 0) {
    const double dv = s.v_m_s - estimate.velocity.v_m_s;
    const double dw = s.w_rad_s - estimate.velocity.w_rad_s;
    sd = std::max(p.alpha * std::sqrt(dv * dv + dw * dw), p.min_random_walk_sigma_m);
    // An absurd measurement (|V_m| ~ 1e200) must not scatter the particles to ∞.
    if (!std::isfinite(sd)) sd = p.random_walk_sigma_m;
  }
  return sd;
}

// Evidence (pf_evolution.h): each parameter's posterior variance inflated by
// `inflate` = e^{dt/M} − 1; the adaptive variant adds eq. 11's σ (unfloored).
void evidence_sigmas(const PfCalibratorParams& p, const CalibEstimate& estimate, const CalibSample& s,
                     long iteration, double inflate, double (&sigma)[3]) {
  double extra = 0.0;
  if (p.adaptive && iteration > 0) {
    const double dv = s.v_m_s - estimate.velocity.v_m_s;
    const double dw = s.w_rad_s - estimate.velocity.w_rad_s;
    extra = p.alpha * std::sqrt(dv * dv + dw * dw);
    if (!std::isfinite(extra)) extra = 0.0;
  }
  const double sds[3] = {estimate.sd_radius_right_m, estimate.sd_radius_left_m, estimate.sd_wheel_base_m};
  const double values[3] = {estimate.params.wheel_radius_right_m, estimate.params.wheel_radius_left_m,
                            estimate.params.wheel_base_m};
  // Bounded forgetting (pf_evolution.h): a parameter's spread is never
  // widened past its prior's (the initial range's uniform sd), so a
  // direction the drive does not excite (D on a circle at one curvature)
  // cannot wind up and wander off.
  const PfCalibratorParams::Range ranges[3] = {p.wheel_radius_right_m, p.wheel_radius_left_m, p.wheel_base_m};
  for (int k = 0; k < 3; ++k) {
    // A cloud that has collapsed onto one value keeps a sliver of spread.
    const double sd = std::max(sds[k], kMinRelativeSpread * values[k]);
    const double prior_sd = (ranges[k].hi - ranges[k].lo) / std::sqrt(12.0);
    const double room = std::max(0.0, prior_sd * prior_sd - sd * sd);
    sigma[k] = std::sqrt(std::min(inflate * sd * sd, room) + extra * extra);
    if (!std::isfinite(sigma[k])) sigma[k] = 0.0;
  }
}

// Whether the policy resamples now, `n` particles with weights summing to
// `weight_sum` (the largest weight is exp(0) = 1).
bool resample_due(const PfCalibratorParams& p, const CalibEstimate& estimate, double n, double weight_sum) {
  bool resample_now = false;
  switch (p.policy) {
    case ResamplePolicy::every_step: resample_now = true; break;
    case ResamplePolicy::neff: resample_now = estimate.n_eff < p.neff_fraction * n; break;
    case ResamplePolicy::max_weight:
      // The largest weight is exp(0) = 1, so max ρ̃ = 1/Σρ.
      resample_now = 1.0 / weight_sum < p.max_weight_ratio / n;
      break;
  }
  return resample_now;
}

// The particle count after resampling: kept, or for the adaptive variant
// set by the radii's dispersion (clamped to [min, max]_particles).
int resample_count(const PfCalibratorParams& p, const CalibEstimate& estimate, int count) {
  if (p.adaptive) {
    const double dispersion = 4.0 * estimate.sd_radius_right_m + 4.0 * estimate.sd_radius_left_m;
    const double wanted = dispersion / p.dispersion_per_particle_m;
    count = std::isfinite(wanted)
                ? static_cast<int>(std::clamp(std::round(wanted), static_cast<double>(p.min_particles),
                                              static_cast<double>(p.max_particles)))
                : p.max_particles;
  }
  return count;
}

}  // namespace

PfCalibratorParams PfCalibratorParams::adaptive_defaults() {
  PfCalibratorParams p;
  p.adaptive = true;
  p.particles = 8000;
  return p;
}

std::string_view to_string(PfEvolution e) { return e == PfEvolution::paper ? "paper" : "evidence"; }

bool parse_pf_evolution(std::string_view text, PfEvolution* out) {
  return core::parse_by_name(text, kAllPfEvolutions, out);
}

bool PfCalibratorParams::IsValid(std::string* why) const {
  if (!check_range("wheel_radius_right_m", wheel_radius_right_m, why) ||
      !check_range("wheel_radius_left_m", wheel_radius_left_m, why) ||
      !check_range("wheel_base_m", wheel_base_m, why))
    return false;
  if (particles < 1) return core::invalid(why, "particles = " + std::to_string(particles) + " must be ≥ 1");
  if (!check_non_negative("random_walk_sigma_m", random_walk_sigma_m, why) ||
      !check_non_negative("v_perturbation_m_s", v_perturbation_m_s, why) ||
      !check_non_negative("w_perturbation_rad_s", w_perturbation_rad_s, why))
    return false;
  if (!(neff_fraction > 0.0 && neff_fraction <= 1.0))
    return core::invalid(why, "neff_fraction = " + num(neff_fraction) + " must be in (0, 1]");
  if (!(std::isfinite(max_weight_ratio) && max_weight_ratio >= 1.0))
    return core::invalid(why, "max_weight_ratio = " + num(max_weight_ratio) +
                                  " must be a finite number ≥ 1 (max ρ ≥ 1/N always)");
  if (!check_non_negative("alpha", alpha, why)) return false;
  if (!(std::isfinite(dispersion_per_particle_m) && dispersion_per_particle_m > 0.0))
    return core::invalid(why, "dispersion_per_particle_m = " + num(dispersion_per_particle_m) +
                                  " must be a finite number > 0");
  if (!check_non_negative("min_random_walk_sigma_m", min_random_walk_sigma_m, why)) return false;
  std::string inner;
  if (!evidence.IsValid(&inner)) return core::invalid(why, "evidence." + inner);
  if (min_particles < 1)
    return core::invalid(why, "min_particles = " + std::to_string(min_particles) + " must be ≥ 1");
  if (max_particles < min_particles)
    return core::invalid(why, "max_particles = " + std::to_string(max_particles) +
                                  " must be ≥ min_particles = " + std::to_string(min_particles));
  if (threads < 0)
    return core::invalid(why, "threads = " + std::to_string(threads) + " must be ≥ 0 (0: OpenMP's default)");
  return true;
}

PfCalibrator::PfCalibrator(const PfCalibratorParams& params) : params_(params), memory_(params.evidence) {
  std::string why;
  if (!params.IsValid(&why)) throw std::invalid_argument("PfCalibratorParams: " + why);
  const auto n = static_cast<std::size_t>(params.particles);
  r_right_.resize(n);
  r_left_.resize(n);
  base_.resize(n);
  v_.assign(n, 0.0);
  w_.assign(n, 0.0);
  log_weight_.assign(n, 0.0);
  weight_.assign(n, 1.0);
  prev_weight_sum_ = static_cast<double>(n);
  // Uniform initial parameters (§III.1), iteration key 0.
  const PfCalibratorParams::Range ranges[] = {params.wheel_radius_right_m, params.wheel_radius_left_m,
                                              params.wheel_base_m};
  std::vector<double>* arrays[] = {&r_right_, &r_left_, &base_};
  for (std::size_t d = 0; d < 3; ++d) {
    const std::uint64_t key = core::counter_hash(params.seed, 0, 0, d, kStreamInit);
    const double lo = ranges[d].lo;
    const double width = ranges[d].hi - ranges[d].lo;
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint64_t bits = core::splitmix64_mix(key + static_cast<std::uint64_t>(i) * kGolden);
      (*arrays[d])[i] = lo + width * (static_cast<double>(bits >> 11) + 0.5) * 0x1.0p-53;
    }
  }
  Shifts shifts;
  shifts.r_right = 0.5 * (params.wheel_radius_right_m.lo + params.wheel_radius_right_m.hi);
  shifts.r_left = 0.5 * (params.wheel_radius_left_m.lo + params.wheel_radius_left_m.hi);
  shifts.base = 0.5 * (params.wheel_base_m.lo + params.wheel_base_m.hi);
  compute_estimate(0.0, shifts);
  estimate_.particles = particle_count();
}

int PfCalibrator::thread_count() const { return params_.threads > 0 ? params_.threads : omp_get_max_threads(); }

const CalibEstimate& PfCalibrator::step(const CalibSample& s) {
  check_sample(s);
  // Step 1: σ of the random walk of R_R, R_L, D.
  double sigma[3];
  if (params_.evolution == PfEvolution::paper) {
    sigma[0] = sigma[1] = sigma[2] = paper_sigma(params_, estimate_, s, iteration_);
  } else {
    const double inflate = iteration_ > 0 ? memory_.step(s.dt_s) : 0.0;
    evidence_sigmas(params_, estimate_, s, iteration_, inflate, sigma);
  }
  ++iteration_;
  const Shifts shifts{estimate_.params.wheel_radius_right_m, estimate_.params.wheel_radius_left_m,
                      estimate_.params.wheel_base_m, s.v_m_s, s.w_rad_s};
  // Steps 1–2.
  const long resets_before = degenerate_resets_;
  double max_log_weight = predict_and_weigh(s, sigma);
  if (!std::isfinite(max_log_weight)) {
    // Every weight is zero or undefined: the sample carries no usable
    // information; start again from equal weights.
    std::fill(log_weight_.begin(), log_weight_.end(), 0.0);
    max_log_weight = 0.0;
    ++degenerate_resets_;
  }
  // Steps 3–4.
  compute_estimate(max_log_weight, shifts);
  log_weight_shift_ = max_log_weight;
  // log p(y_k | y_1..k−1) = log Σ ρ_{k−1}·N(y; ŷ_i, var) − log Σ ρ_{k−1}
  // (header), the Gaussian's normalisation included.
  last_log_predictive_ = max_log_weight + std::log(block_sums_[kSumW]) - std::log(prev_weight_sum_) -
                         std::log(2.0 * std::numbers::pi) + 0.5 * std::log(last_inv_var_product_);
  if (degenerate_resets_ > resets_before) last_log_predictive_ = std::nan("");
  prev_weight_sum_ = block_sums_[kSumW];

  const double n = static_cast<double>(particle_count());
  const bool resample_now = resample_due(params_, estimate_, n, block_sums_[kSumW]);
  if (resample_now) resample_to(resample_count(params_, estimate_, particle_count()));
  estimate_.resampled = resample_now;
  estimate_.particles = particle_count();
  return estimate_;
}

double PfCalibrator::predict_and_weigh(const CalibSample& s, const double (&sigma_m)[3]) {
  const std::size_t n = r_right_.size();
  const std::size_t blocks = block_count(n);
  block_sums_.assign(blocks * kSumCount, 0.0);
  const auto it = static_cast<std::uint64_t>(iteration_);
  PredictInputs in{};
  in.key_radii = core::counter_hash(params_.seed, it, 0, 0, kStreamWalkRadii);
  in.key_base = core::counter_hash(params_.seed, it, 0, 0, kStreamWalkBase);
  in.key_velocity = core::counter_hash(params_.seed, it, 0, 0, kStreamVelocity);
  in.sigma_rr = sigma_m[0];
  in.sigma_rl = sigma_m[1];
  in.sigma_d = sigma_m[2];
  in.omega_l = s.omega_l_rad_s;
  in.omega_r = s.omega_r_rad_s;
  in.v_m = s.v_m_s;
  in.w_m = s.w_rad_s;
  if (params_.evolution == PfEvolution::evidence) {
    // The perturbation integrated out (header): no draw, its variance a²/3
    // added to the measurement's.
    const double a_v = params_.v_perturbation_m_s, a_w = params_.w_perturbation_rad_s;
    in.a_v = in.a_w = 0.0;
    in.inv_v_var = 1.0 / (s.v_var + a_v * a_v / 3.0);
    in.inv_w_var = 1.0 / (s.w_var + a_w * a_w / 3.0);
  } else {
    in.a_v = params_.v_perturbation_m_s;
    in.a_w = params_.w_perturbation_rad_s;
    in.inv_v_var = 1.0 / s.v_var;
    in.inv_w_var = 1.0 / s.w_var;
  }
  in.log_weight_shift = log_weight_shift_;
  last_inv_var_product_ = in.inv_v_var * in.inv_w_var;
  double* r_right = r_right_.data();
  double* r_left = r_left_.data();
  double* base = base_.data();
  double* v = v_.data();
  double* w = w_.data();
  double* log_weight = log_weight_.data();
  double* maxima = block_sums_.data();
  const bool perturb = in.a_v != 0.0 || in.a_w != 0.0;
  const int threads = thread_count();
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && blocks > 1)
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::size_t i0 = b * kBlock;
    maxima[b * kSumCount] =
        perturb
            ? predict_block<true>(in, r_right, r_left, base, v, w, log_weight, i0, std::min(n, i0 + kBlock))
            : predict_block<false>(in, r_right, r_left, base, v, w, log_weight, i0, std::min(n, i0 + kBlock));
  }
  double m = -std::numeric_limits<double>::infinity();
  for (std::size_t b = 0; b < blocks; ++b) m = std::max(m, maxima[b * kSumCount]);
  return m;
}

void PfCalibrator::compute_estimate(double max_log_weight, const Shifts& sh) {
  const std::size_t n = r_right_.size();
  const std::size_t blocks = block_count(n);
  block_sums_.assign(blocks * kSumCount, 0.0);
  const double* r_right = r_right_.data();
  const double* r_left = r_left_.data();
  const double* base = base_.data();
  const double* v = v_.data();
  const double* w = w_.data();
  const double* log_weight = log_weight_.data();
  double* weight = weight_.data();
  double* sums = block_sums_.data();
  const EstimateInputs in{max_log_weight, kMinLogWeight, pf_kernels::ExpClamp{}, sh.r_right, sh.r_left, sh.base,
                          sh.v,           sh.w};
  const int threads = thread_count();
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && blocks > 1)
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::size_t i0 = b * kBlock;
    estimate_block(in, r_right, r_left, base, v, w, log_weight, weight, i0, std::min(n, i0 + kBlock),
                   sums + b * kSumCount);
  }
  // Combine the blocks in block order (into block 0's slots).
  for (std::size_t b = 1; b < blocks; ++b)
    for (std::size_t k = 0; k < kSumCount; ++k) sums[k] += sums[b * kSumCount + k];
  const double inv = 1.0 / sums[kSumW];
  auto sd_of = [inv](double s1, double s2) {
    const double mean = s1 * inv;
    return std::sqrt(std::max(0.0, s2 * inv - mean * mean));
  };
  estimate_.params.wheel_radius_right_m = sh.r_right + sums[kSumRr] * inv;
  estimate_.params.wheel_radius_left_m = sh.r_left + sums[kSumRl] * inv;
  estimate_.params.wheel_base_m = sh.base + sums[kSumBase] * inv;
  estimate_.velocity.v_m_s = sh.v + sums[kSumV] * inv;
  estimate_.velocity.w_rad_s = sh.w + sums[kSumWz] * inv;
  estimate_.sd_radius_right_m = sd_of(sums[kSumRr], sums[kSumRr2]);
  estimate_.sd_radius_left_m = sd_of(sums[kSumRl], sums[kSumRl2]);
  estimate_.sd_wheel_base_m = sd_of(sums[kSumBase], sums[kSumBase2]);
  // N_eff = 1/Σρ̃² = (Σρ)²/Σρ² (eq. 10).
  estimate_.n_eff = sums[kSumW] * sums[kSumW] / sums[kSumW2];
}

void PfCalibrator::resample_to(int count) {
  const auto m = static_cast<std::size_t>(count);
  ancestors_.resize(m);
  resample(params_.resampler, weight_, params_.seed, static_cast<std::uint64_t>(iteration_), ancestors_);
  next_r_right_.resize(m);
  next_r_left_.resize(m);
  next_base_.resize(m);
  const int* anc = ancestors_.data();
  const double* r_right = r_right_.data();
  const double* r_left = r_left_.data();
  const double* base = base_.data();
  double* nr = next_r_right_.data();
  double* nl = next_r_left_.data();
  double* nb = next_base_.data();
  const std::size_t blocks = block_count(m);
  const int threads = thread_count();
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && blocks > 1)
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::size_t j1 = std::min(m, (b + 1) * kBlock);
    for (std::size_t j = b * kBlock; j < j1; ++j) {
      const auto a = static_cast<std::size_t>(anc[j]);
      nr[j] = r_right[a];
      nl[j] = r_left[a];
      nb[j] = base[a];
    }
  }
  r_right_.swap(next_r_right_);
  r_left_.swap(next_r_left_);
  base_.swap(next_base_);
  // Velocities are recomputed by the next prediction; weights restart equal.
  v_.resize(m);
  w_.resize(m);
  log_weight_.assign(m, 0.0);
  weight_.resize(m);  // rewritten by the next compute_estimate()
  log_weight_shift_ = 0.0;
  prev_weight_sum_ = static_cast<double>(m);  // equal weights exp(0)
}

}  // namespace odotune::filters
