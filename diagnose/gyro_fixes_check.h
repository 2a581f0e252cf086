// The gyro judged against sparse absolute POSITION fixes (no reference
// heading), a companion of sensor_checks.h (docs/diagnosis-design.md step 5),
// whose gyro regression needs a reference heading.
//
// Why. With fixes only, the gyro's yaw and the wheels' yaw can be compared
// with each other but not with the truth: gyro_scale and wheel_base_error are
// confounded in their ratio. Positions decide it: dead reckoning whose
// heading comes from the GYRO and whose distance comes from the WHEELS
// follows the fixes only when the gyro is right. Wheel heading errors
// (wheel_base_error, unequal radii) do not enter it at all; the wheels'
// mean distance does, and a common distance scale q is fitted with the gyro
// (fit_distance_scale) so that a radius error is not blamed on the gyro.
//
// Model (physics-effects.md: the gyro reads s*w + b; gyro_dead_reckoning.h
// implements it). Per odometry interval k (nodes t_k -> t_{k+1} of
// DiagInput::odo_t_s):
//   heading   theta(t_k) = theta0 + (G(t_k) - G(t_a) - b*(t_k - t_a))/s,
//             G = the exact integral of the gyro samples' linear interpolant,
//             t_a = the window's anchor time (corrected_gyro_rate integrated);
//   distance  ds_k = q*(S(t_{k+1}) - S(t_k)), S = the mean of the nominal
//             cumulative rim travels of EffectModel's OdoSeries without
//             effects (wheel angles x nominal radii, or the integrated body
//             speed); q = 1 unless fit_distance_scale;
//   position  the arc update of effect_model.h's advance() with the
//             interval's heading change; a fix between two nodes is
//             predicted by linear interpolation, as in window_replay.h.
//
// Windows: make_windows(in, window_s) of window_replay.h, window_s shortened
// to max(min_window_s, span/3) on a track whose reference spans fewer than
// three of them (GyroFixesCheck::window_s is the one used) (a last window
// shorter than window_s/2 joins the one before: its few fixes would hardly
// constrain its own anchor, nor show a heading drift), each with a free
// anchor pose (x0, y0, theta0) [m, m, rad], a nuisance parameter as in fit.h
// with fixes only, started at the closed-form rigid alignment of the
// nominal gyro dead reckoning (s = 1, b = 0) onto the window's fixes. Used
// windows: at least 3 scored reference samples, inside the gyro's time span,
// and a nominal dead reckoning that spreads (RMS distance from its centroid)
// at least min_spread_sigmas*ref_sigma_m (else the anchor heading is
// unobservable); the others are listed in skipped_windows. Only reference
// POSITIONS are used, even when the reference has a heading (sensor_checks.h
// is then the stronger test).
// Window length. The free anchor absorbs a heading error's constant and, in
// effect, linear part, so what remains of a drift grows about as T^2 within
// a window of T seconds, against fix noise that does not grow: 40 s by
// default, twice fit.h's 20 s. Measured on the concealed suite's
// gyro_scale_fixes_only (s = 0.995, 50 mm fixes at 1 Hz): with 20-30 s
// windows no held-out window shows the fitted scale (the test cannot pass),
// with 40-50 s it passes; longer windows leave too few windows for the
// jackknife and the held-out split of a 200 s track.
//
// Standstill (use_standstill; wheel-angle odometry only). Where both wheels'
// angles do not change over consecutive odometry intervals, trimmed by
// standstill_trim_s at both ends and lasting at least min_standstill_s, the
// body does not turn (a differential drive cannot turn with both wheels
// still), so the gyro's mean there is b: residual (mean - b)/sigma_r,
// sigma_r = sigma_g*sqrt(dt_gyro/duration) (sigma_g the gyro's white noise,
// floored at 1e-5 rad/s), robustified as a fix's. It separates b from s,
// which positions alone confound when the robot turns at a steady mean rate
// (a bias then looks like a scale error). Each run belongs to the used
// window holding its middle (else the nearest), and goes with that window
// in every fit and held-out score. Commanded velocities (body_velocity) are
// not used: a zero command does not mean that the body has stopped turning.
//
// Fit (Ceres, Levenberg-Marquardt, dense QR): s, b (within the effect
// table's ranges, tracks/effects.h) [, q in [0.5, 1.5]] and one anchor per
// window; residual per fix = (predicted - fix)/ref_sigma_m per axis,
// robustified per FIX on its 2D norm u = |e|^2 (rotation-invariant):
// e -> e*sqrt(rho(u)/u), rho = Huber or Cauchy of scale loss_scale [sigmas]
// (fit.h robustifies per axis; one bad fix is down-weighted either way).
//
// Standard errors: max(jackknife, model-based).
//  * Delete-one-window JACKKNIFE over the used windows (each refit
//    warm-started from the all-window fit): se^2 = (n-1)/n *
//    sum_i (v_(i) - mean)^2 (Efron & Stein 1981; valid for smooth
//    M-estimators). Dead-reckoning residuals are correlated within a window
//    (gyro random walk, encoder quantisation, the shared anchor), which a
//    covariance assuming independent residuals misses; windows are nearly
//    independent blocks (each has its own anchor), so resampling whole
//    windows keeps that correlation. Deterministic (no seed): n refits, where
//    a window bootstrap would need hundreds and, with 4-6 windows, has no
//    more information.
//  * Model-based (Gauss-Newton): (J'J)^-1 at the all-window solution, scaled
//    by the residual variance factor 2*cost/(m - n) (as fit.h); NaN when J'J
//    scaled to a unit diagonal has an eigenvalue below 1e-10 of the largest
//    (e.g. a robot that never turns: s unobservable).
//  With 4-6 windows the jackknife is itself noisy and can come out small by
//  chance (measured: down to a third of the model-based value); the
//  model-based error is the floor, the jackknife adds the correlation it
//  misses. A NaN of either gives a NaN standard error (no verdict).
//
// Held-out proof. The used windows in time order are split: the first
// (1 - heldout_fraction) train a fit of (s, b [, q]); the rest (at least 1,
// and at least 2 train) are held out. On each held-out window, two parameter
// sets are replayed with closed-form anchors (the rigid alignment, Kabsch
// without scale, of each prediction onto the window's fixes) and compared:
//   joint:         the training fit against s = 1, b = 0 (q as trained);
//   gyro_scale.s:  the training fit against s = 1 (b, q as trained);
//   gyro_bias.b:   the training fit against b = 0 (s, q as trained).
// Per window w: SSE_ref(w), SSE_alt(w) = sum over its fixes of
// |pred - fix|^2/sigma^2 plus, over its standstill runs, ((mean - b)/
// sigma_r)^2 (no robust loss); D_w = the same sums of the squared
// differences of the two predictions; informative when D_w >=
// min_informative; z_w = (SSE_ref - SSE_alt)/(2 s_w sqrt(D_w)), s_w^2 =
// max(1, SSE_alt/terms) (terms = 2 per fix + 1 per run). That is the
// white-noise law of the difference: were the reference set true,
// SSE_ref - SSE_alt would have mean -D_w and standard deviation 2 sqrt(D_w),
// and were the alternative true, mean +D_w; inflated when the residual
// exceeds the noise (as CrossValidator::compare, cross_validate.h). Stouffer:
// Z = sum z_w / sqrt(m) over the m informative windows, p = P(N(0,1) > Z),
// passed when m >= 1 and p < alpha. (A rank test over windows, e.g.
// paired_test.h's Wilcoxon, cannot go below 2^-m: 0.25 for the 2 held-out
// windows of a 200 s track.)
//
// Verdicts (sensor_checks.h's Verdict, so both gyro checks read alike):
// value = the all-window fit, std_error as above, z = (value - noop)/
// std_error; drift/noise_drift as sensor_checks.h (heading drift over
// relevance_window_s T: |s - 1|*mean|w|*T with mean|w| the mean absolute
// corrected gyro rate over the used windows' span, |b|*T; noise: the
// random walk of the gyro's white noise sigma_g*sqrt(T*dt_gyro), sigma_g =
// 1.4826*MAD of second differences / sqrt(6)). significant = |z| >
// z_threshold AND the parameter's own held-out test passed (HERE
// "significant" includes the held-out proof, so noise alone yields no
// verdict). The joint test is reported, not required: a parameter that
// proves itself against the trained model without it is proven, and the
// joint test of a scale error beside an idle bias is diluted by the bias's
// noise (a benchmark case: own p = 0.0006, joint
// 0.0011 over 3 held-out windows, z = 9.7); relevant = drift > max(relevance_factor*noise_drift,
// min_drift_rad).
//
// No I/O. SI units. Deterministic (no randomness).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "diagnose/diag_input.h"
#include "diagnose/effect_model.h"
#include "diagnose/fit.h"
#include "diagnose/sensor_checks.h"

namespace odotune::diagnose {

struct GyroFixesOptions {
  double window_s = 40.0;  // replay window [s] (make_windows; > 0); see header
  // A track shorter than 3 windows gets windows of a third of its span, but
  // not shorter than this [s] (a 71 s track: 3 windows of 23.7 s instead of
  // 2 of 40 s, too few for a held-out proof).
  double min_window_s = 20.0;
  RobustLoss loss = RobustLoss::huber;
  double loss_scale = 3.0;         // where the loss turns robust [fix sigmas]
  int max_iterations = 100;        // Levenberg-Marquardt iterations per fit
  double min_spread_sigmas = 2.0;  // windows whose dead reckoning moves less are not used
  bool fit_distance_scale = true;  // also fit q, a common scale of the wheel distance
  bool use_standstill = true;      // gyro means where both wheels stand still constrain b
  double min_standstill_s = 0.5;   // shortest standstill run used (after trimming) [s]
  double standstill_trim_s = 0.1;  // cut from both ends of a standstill run [s]
  double heldout_fraction = 0.3;   // share of the used windows held out (the last ones)
  double alpha = 1e-3;             // one-sided level of the held-out test
  double min_informative = 4.0;    // D_w a held-out window needs [normalised units]
  // As SensorCheckOptions (same meaning and defaults):
  double z_threshold = 4.0;          // significance: |value - noop| > z*std_error
  double relevance_window_s = 20.0;  // T of the relevance test [s]
  double relevance_factor = 2.0;     // drift must exceed this x noise drift ...
  double min_drift_rad = 1e-3;       // ... and this [rad]
  ModelOptions model;                // of the EffectModel giving the nominal distance

  bool IsValid(std::string* why) const;
};

// One held-out comparison (header comment): `alt` = the training fit,
// `ref` = the same with the tested parameters at their no-op values.
struct HeldoutComparison {
  std::string what;     // "joint", "gyro_scale.s", "gyro_bias.b"
  int windows = 0;      // held-out windows scored
  int informative = 0;  // of those, D_w >= min_informative
  int improved = 0;     // informative windows where SSE_alt < SSE_ref
  double ref_pos_rmse_m = std::numeric_limits<double>::quiet_NaN();  // pooled, held-out
  double alt_pos_rmse_m = std::numeric_limits<double>::quiet_NaN();
  double z = std::numeric_limits<double>::quiet_NaN();  // Stouffer's Z
  double p = 1.0;                                       // one-sided
  bool passed = false;                                  // informative >= 1 and p < alpha
};

struct GyroFixesCheck {
  // Verdicts: value/std_error/z/drift as the header comment. bins = used
  // windows; residual_sigma_radps is NaN (no rate regression here).
  GyroCheck gyro;
  int standstill_runs = 0;      // used standstill runs
  double standstill_s = 0.0;    // their total duration [s]
  double distance_scale = 1.0;  // fitted q (1 unless fit_distance_scale)
  double distance_scale_std_error = std::numeric_limits<double>::quiet_NaN();

  // The two standard errors behind Verdict::std_error = max(jackknife, model).
  double scale_jackknife_se = std::numeric_limits<double>::quiet_NaN();
  double scale_model_se = std::numeric_limits<double>::quiet_NaN();
  double bias_jackknife_se = std::numeric_limits<double>::quiet_NaN();
  double bias_model_se = std::numeric_limits<double>::quiet_NaN();

  // Window indices are make_windows(in, window_s)'s (a short last window
  // merged into the one before counts as that one).
  double window_s = 0.0;
  int num_windows = 0;                              // windows after the merge
  std::vector<int> used_windows;                    // fitted (all-window fit, jackknife)
  std::vector<int> skipped_windows;                 // outside the gyro, too few fixes, or no motion
  std::vector<int> train_windows, heldout_windows;  // split of used_windows
  double train_scale = std::numeric_limits<double>::quiet_NaN();  // training fit
  double train_bias_radps = std::numeric_limits<double>::quiet_NaN();
  HeldoutComparison joint, scale_own, bias_own;

  // In-sample position RMSE over the used windows (closed-form anchors):
  // nominal gyro dead reckoning (s = 1, b = 0, q = 1) and the all-window fit.
  double nominal_pos_rmse_m = std::numeric_limits<double>::quiet_NaN();
  double fitted_pos_rmse_m = std::numeric_limits<double>::quiet_NaN();
  bool converged = false;  // the all-window fit converged
  int fits = 0;            // Ceres solves (1 + training + jackknife)
  double time_s = 0.0;     // wall clock
};

// Throws std::invalid_argument (one line) for invalid options or an input
// whose arrays are inconsistent. An input the check cannot judge (no gyro,
// no wheel distance, fewer than 3 usable windows, ...) gives
// gyro.available = false and gyro.unavailable_reason.
GyroFixesCheck check_gyro_with_fixes(const DiagInput& in, const GyroFixesOptions& options = {});

}  // namespace odotune::diagnose
