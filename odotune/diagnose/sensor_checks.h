// Step 5 of the diagnosis: every sensor against what the reference implies,
// before any model is fitted: reference rates over bins, the gyro and wheel
// ratios by whitened increment regression with bootstrap standard errors,
// verdicts (significant and relevant), and the odometry's and commands' lags.
// The method, its rules and their reasons: docs/diagnosis-design.md,
// "Sensor checks". No I/O. Everything in SI units.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <odotune/diagnose/diag_input.h>

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
