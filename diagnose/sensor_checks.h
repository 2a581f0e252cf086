// Step 5 of the diagnosis (docs/diagnosis-design.md): every sensor against
// what the reference implies, before any model is fitted.
//
//  * Reference rates. The reference is cut into consecutive, non-overlapping
//    bins [t0, t1] whose edges are reference samples (so no interpolation of
//    the reference is needed): with ground truth each bin spans at least
//    `bin_s`, with position fixes only at least max(bin_s, aps_min_bin_s).
//    A bin's reference yaw rate is Δθ/(t1 − t0), Δθ = θ(t1) − θ(t0), and its
//    speed the displacement along the mean heading (θ(t0)+θ(t1))/2 divided
//    by (t1 − t0)·sinc(Δθ/2) (signed: reversing gives v < 0; the sinc turns
//    the chord of a circular arc into its length, exactly for constant
//    curvature, so turning does not bias the speed low). Without a reference
//    heading the speed is the chord |p(t1) − p(t0)|/(t1 − t0) (≥ 0) and there
//    is no yaw rate. These are exact MEAN rates over the bin (a central
//    difference, i.e. a derivative smoothed by a box filter of width
//    t1 − t0); every sensor is reduced to its mean over the very same
//    interval, so changing velocities do not bias the comparison. 0.25 s
//    holds 25 gyro samples at 100 Hz.
//    Gaps: no bin spans a step between reference samples longer than
//    max(2 bin widths, 5 median reference periods); the next bin starts at
//    the sample after the gap. Over a gap the chord is not the path (the
//    speed would come out low wherever the robot turned in it) and a bin's
//    error is no longer one reference sample's noise at each edge; the
//    regression's whitening (below) restarts after a skipped bin, since the
//    bins beside it share no edge sample.
//
//  * Regression (gyro and wheel ratios) in INCREMENT form over the bins:
//    reference increment = coefficients × sensor increments + e_k. The
//    error of bin k is e_k = (n_{k+1} − n_k) + m_k: the white noise n of the
//    reference's two edge samples (σ estimated from the reference itself,
//    1.4826·MAD of second differences / √6, or DiagInput::ref_sigma_m for
//    positions) makes neighbouring bins anti-correlated; m is the sensor's
//    own noise over the bin (gyro: its white noise integrated, σ_g²·Δt·width;
//    encoders: quantisation, one count = the smallest wheel-angle step).
//    The tridiagonal covariance is whitened by its bidiagonal Cholesky
//    factor (generalised least squares): efficient whether the reference's
//    noise dominates (it then amounts to regressing the heading LEVELS, so a
//    gyro bias is measured over the whole track rather than per bin) or the
//    sensor's noise does. The reference is the response and the sensor the
//    regressor, because the sensor's bin integral is the nearly noise-free
//    side (the other way round, noise in the reference would attenuate the
//    slope: the errors-in-variables bias). Then a Huber M-estimator by
//    iteratively reweighted least squares (scale 1.4826·MAD).
//    Standard errors: block residual bootstrap: the whitened residuals are
//    resampled in moving blocks of `bootstrap_block_s` (keeping any
//    autocorrelation the noise model missed: unmodelled effects, slow
//    drifts), added to the fitted values, refitted; `bootstrap_replicates`
//    replicates, std::mt19937_64 seeded with `seed`.
//
//  * Gyro bins. The gyro regression has bins of its own, at least
//    max(gyro_bin_s, 2 gyro periods) wide (never wider than bin_s): in
//    increment form the bin width does not bias anything (the gyro's bin
//    integral is exact), and every reference heading the bins keep lowers
//    the level noise of b and s. With 0.25 s bins a 25 Hz reference kept one
//    heading in six, and its 16 mrad noise left a 0.2 mrad/s gyro bias at 2
//    standard errors over 165 s (over 24 seeds of that setting the bootstrap standard error matched the spread).
//  * Gyro: gyro = s·w + b (physics-effects.md), i.e. Δθ_ref = α·Δψ_gyro +
//    β·(t1 − t0) with s = 1/α, b = −β/α; Δψ_gyro is the exact integral of
//    the gyro samples' linear interpolant. Needs a reference heading. The
//    gyro's white noise σ is estimated from its samples alone (1.4826·MAD of
//    second differences / √6).
//
//  * Verdicts. A parameter departs from its no-op value (s = 1, b = 0) when
//    it is significant, |value − noop| > z_threshold·stderr, AND practically
//    relevant: the heading drift it causes over `relevance_window_s`
//    (|b|·T, or |s − 1|·mean|w_ref|·T) exceeds `relevance_factor` times the
//    heading random walk of the gyro's white noise over the same window,
//    σ·√(T·Δt_gyro), and an absolute floor (min_drift_rad / min_drift_m: a
//    departure that moves the dead reckoning by less than a millimetre-scale
//    amount over T is irrelevant however well it is determined).
//
//  * Wheel odometry (nominal kinematics of track-format.md). Per bin:
//    odometry distance and heading change over [t0, t1] from the cumulative
//    wheel angles (linear interpolation) × nominal radii, or from the body
//    velocities integrated as linear between stamps (so a held-sample
//    convention's half-period delay does not show as lag). Ratios reference
//    / odometry of distance (and of heading change, with a reference
//    heading), regression through the origin as above. With fixes only the
//    odometry's chord over the bin (dead reckoning with nominal kinematics)
//    is compared with the fixes' chord, both rotation-invariant.
//  * Lags (evidence for time_offset / actuator_lag; the fit is fit.h's job).
//    The odometry is re-evaluated over bins shifted by τ on a grid of
//    `lag_step_s` (default: the median odometry period, at least 1/25 of the
//    mean bin width) within ±max_lag_s; the Pearson correlation of the
//    reference rates with the shifted odometry rates (mean of the speed and
//    yaw-rate correlations when both exist) is maximised and refined by a
//    parabola through the peak and its two neighbours. Stderr: moving-block
//    bootstrap of the bins.
//      odometry_late: odo(t) ≈ ref(t − lag); + = odometry stamped late
//        (time_offset.dt > 0). With commanded/base-reported body velocities
//        as odometry an actuator lag shows as a negative value.
//      command_delay: ref(t) ≈ cmd(t − lag); + = the body follows the
//        commands late (a first-order actuator_lag of time constant tau
//        delays a ramp by tau). Only when the input has commands next to
//        wheel odometry.
//
// No I/O. Everything in SI units.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "diagnose/diag_input.h"

namespace odotune::diagnose {

struct SensorCheckOptions {
  double bin_s = 0.25;         // minimum width of a reference bin [s]
  double gyro_bin_s = 0.05;    // ... of the gyro regression's bins, at least 2 gyro periods [s]
  double aps_min_bin_s = 2.0;  // minimum bin width with fixes only [s]
  double huber_k = 1.345;      // Huber threshold, in robust residual σ
  int max_irls_iterations = 50;
  int bootstrap_replicates = 200;
  double bootstrap_block_s = 5.0;    // block length of the bootstrap [s]
  std::uint64_t seed = 1;            // bootstrap RNG seed
  double z_threshold = 4.0;          // significance: |value − noop| > z·stderr
  double relevance_window_s = 20.0;  // T of the relevance test [s]
  double relevance_factor = 2.0;     // drift must exceed this × noise drift ...
  double min_drift_rad = 1e-3;       // ... and this [rad] (gyro, yaw_ratio) ...
  double min_drift_m = 2e-3;         // ... or this [m] (speed_ratio)
  double max_lag_s = 0.5;            // lag search range ±[s]
  double lag_step_s = 0.0;           // lag grid step [s]; 0 = auto (file comment)

  bool IsValid(std::string* why) const;
};

// One tested quantity: a parameter of physics-effects.md (name "effect.param")
// or an evidence ratio ("speed_ratio", "yaw_ratio").
struct Verdict {
  std::string name;
  double value = std::numeric_limits<double>::quiet_NaN();
  double std_error = std::numeric_limits<double>::quiet_NaN();  // block residual bootstrap
  double noop = 0.0;                                            // the value meaning "no effect"
  double z = std::numeric_limits<double>::quiet_NaN();          // (value − noop)/std_error
  // Drift the departure causes over relevance_window_s, and the drift the
  // noise alone causes. Gyro [rad]: the heading random walk of its white
  // noise. speed_ratio [m] / yaw_ratio [rad]: the robust residual σ of the
  // ratio regression × the mean bin width, i.e. the noise of one bin's
  // reference displacement (heading change): a departure drifting less than
  // that over T cannot be told from the reference's own noise.
  double drift = std::numeric_limits<double>::quiet_NaN();
  double noise_drift = std::numeric_limits<double>::quiet_NaN();
  bool significant = false;  // |z| > z_threshold
  bool relevant = false;     // drift > max(relevance_factor · noise_drift, floor)
  bool departs() const { return significant && relevant; }
};

// Reference rates per bin (see the file comment).
struct ReferenceBins {
  std::vector<double> t0_s, t1_s;
  std::vector<double> v_mps;    // gt: signed speed along the mean heading; aps: chord speed
  std::vector<double> w_radps;  // gt: mean yaw rate; aps: empty
  bool heading = false;         // true when v is signed and w exists (gt)
  // White noise of one reference sample: heading [rad] (gt; robust, from
  // second differences of θ) and position per axis [m] (DiagInput's
  // ref_sigma_m when > 0, else from second differences of x, y for gt, else 0).
  double heading_noise_rad = 0.0;
  double position_noise_m = 0.0;
};

struct GyroCheck {
  bool available = false;
  std::string unavailable_reason;  // e.g. "no gyro", "no reference heading"
  int bins = 0;
  double noise_sigma_radps = std::numeric_limits<double>::quiet_NaN();     // per sample
  double residual_sigma_radps = std::numeric_limits<double>::quiet_NaN();  // per bin, robust
  double mean_abs_rate_radps = std::numeric_limits<double>::quiet_NaN();   // mean |w_ref|
  Verdict scale;                                                           // "gyro_scale.s", noop 1
  Verdict bias;                                                            // "gyro_bias.b" [rad/s], noop 0
};

struct LagEstimate {
  bool available = false;
  double lag_s = std::numeric_limits<double>::quiet_NaN();
  double std_error_s = std::numeric_limits<double>::quiet_NaN();
  double peak_correlation = std::numeric_limits<double>::quiet_NaN();
  bool at_edge = false;  // the peak is at ±max_lag_s (true lag may be larger)
};

struct OdometryCheck {
  bool available = false;
  std::string unavailable_reason;
  int bins = 0;
  double residual_sigma_mps = std::numeric_limits<double>::quiet_NaN();  // speed regression, per bin
  Verdict speed_ratio;        // reference / odometry ground speed, noop 1
  Verdict yaw_ratio;          // reference / odometry yaw rate, noop 1 (gt only)
  LagEstimate odometry_late;  // odo(t) ≈ ref(t − lag)
  LagEstimate command_delay;  // ref(t) ≈ cmd(t − lag)
};

struct SensorCheck {
  ReferenceBins reference;
  GyroCheck gyro;
  OdometryCheck odometry;
};

// Reference bins over [t_begin, t_end] ∩ the reference's span. Throws
// std::invalid_argument (one line) for invalid options or input.
ReferenceBins reference_bins(const DiagInput& in, const SensorCheckOptions& options,
                             double t_begin_s = -std::numeric_limits<double>::infinity(),
                             double t_end_s = std::numeric_limits<double>::infinity());

// All checks. A check that the input cannot support is returned with
// available = false and the reason; throws std::invalid_argument (one line)
// for invalid options or inconsistent input (mismatched array lengths,
// non-increasing time).
SensorCheck check_sensors(const DiagInput& in, const SensorCheckOptions& options = {});

}  // namespace odotune::diagnose
