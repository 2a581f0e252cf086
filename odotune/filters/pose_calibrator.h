// Online pose-domain odometry calibration: an extended Kalman filter over the
// pose and the geometry, s = (x, y, θ, R_L, R_R, D), driven by the wheel
// encoders and corrected by absolute position fixes (GNSS, motion capture,
// UWB, a localiser's pose) with their variances. The online counterpart of
// odotune/calibration/pose_calibration.h: its information is where the dead
// reckoning lands, not derived body velocities. Design: docs/calibration/
// online-pose.md.
//
// Predict, over an encoder interval with wheel angles Δφ_L, Δφ_R [rad]:
//   l = R_L·Δφ_L, r = R_R·Δφ_R; the pose by the midpoint step of
//   odotune/core/planar_motion.h (odotune/filters/diff_drive.h with its Jacobians); the
//   geometry is constant; P⁻ = F P Fᵀ + G Q Gᵀ with F = ∂s'/∂s,
//   G = ∂s'/∂(l, r) and Q = diag(k·|l|, k·|r|), k = wheel_noise_m2_per_m
//   (random wheel error whose variance grows with the distance rolled).
// Fade, before each fix, after the wheels rolled Δs metres since the
//   previous one (Δs = Σ(|l| + |r|)/2): the geometry's share of P is widened,
//   P ← S P S with S = diag(1, 1, 1, s, s, s), s² = e^{Δs/M}, no geometry
//   variance past its initial one. The memory M is a distance (a geometry
//   error shows in proportion to the distance rolled, and a robot standing
//   still forgets nothing); it grows like odotune/filters/pf_evolution.h's evidence
//   memory, in metres instead of seconds.
// Update with a fix z = (x, y), R = diag(var_x, var_y): H = [I₂ 0],
//   Joseph form. Gate: a fix whose normalised innovation squared exceeds
//   gate_nis is not applied (an outlier); after max_rejected_fixes in a row
//   the pose is taken as lost, and the next fix is applied with the pose's
//   covariance widened to hold it.
// Start: known (a pose and its sds) or from the fixes: until then the filter
//   dead-reckons with the initial geometry in its own frame and collects
//   (odometry position, fix) pairs; once the fixes spread by
//   acquire_spread_sigmas fix sds about their mean, the rigid motion that
//   maps the odometry positions onto the fixes (2-D Kabsch) places the pose
//   where the acquisition began, and its samples are run through the filter
//   from there, so that its fixes inform the geometry as well.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <odotune/filters/odometry_params.h>
#include <odotune/filters/pf_evolution.h>

namespace odotune::filters {

// Named indices of the state.
enum PoseCalibIndex : int {
  kPcX = 0,
  kPcY = 1,
  kPcTheta = 2,
  kPcRadiusLeft = 3,
  kPcRadiusRight = 4,
  kPcWheelBase = 5,
  kPcDim = 6
};

using PcState = Eigen::Matrix<double, kPcDim, 1>;
using PcCov = Eigen::Matrix<double, kPcDim, kPcDim>;
using PcJacobian = Eigen::Matrix<double, kPcDim, kPcDim>;
using PcNoiseJacobian = Eigen::Matrix<double, kPcDim, 2>;

// The geometry's memory, in metres rolled: M starts at min_memory_m after a
// (re)start and grows with the distance up to max_memory_m.
struct DistanceMemoryParams {
  double min_memory_m = 10.0;    // M at the (re)start; the fast twin's fixed M
  double max_memory_m = 1000.0;  // the longest memory

  // True when usable; otherwise *why names the first bad value.
  bool IsValid(std::string* why) const;
};
// The fast twin of odotune/filters/memory_pair.h: its memory stays at the minimum.
inline DistanceMemoryParams fast_twin(const DistanceMemoryParams& p) {
  return {p.min_memory_m, p.min_memory_m};
}

struct PoseCalibratorParams {
  OdometryParams initial;                    // geometry at the start (the robot's nominal values)
  double initial_sd_radius_frac = 0.02;      // prior sd of each radius, as a fraction of it
  double initial_sd_wheel_base_frac = 0.05;  // prior sd of D, as a fraction of it
  double wheel_noise_m2_per_m = 1e-6;        // k: variance of a wheel's travel per metre rolled [m²/m]
  double gate_nis = 25.0;                    // NIS above which a fix is an outlier (χ²₂: p ≈ 4·10⁻⁶)
  int max_rejected_fixes = 5;                // in a row, then the pose is re-acquired
  double acquire_spread_sigmas = 4.0;        // start from fixes: their RMS spread, in fix sds
  int acquire_min_fixes = 3;                 // ... and at least this many fixes
  DistanceMemoryParams memory;               // the geometry's fading memory

  // True when usable; otherwise *why names the first bad value.
  bool IsValid(std::string* why) const;
};

// One input: an encoder interval, then optionally a fix at its end.
// Contract: dt_s ≥ 0, wheel angles finite; with has_fix the fix finite and
// its variances > 0.
struct PoseCalibSample {
  double dt_s = 0.0;           // length of the encoder interval [s]
  double dphi_left_rad = 0.0;  // wheel angles turned over it [rad]
  double dphi_right_rad = 0.0;
  bool has_fix = false;
  double fix_x_m = 0.0, fix_y_m = 0.0;
  double fix_var_x_m2 = 0.0, fix_var_y_m2 = 0.0;
};

// The prediction's Jacobians at state s for wheel angles (Δφ_L, Δφ_R), and
// the predicted state (checked against finite differences in the tests).
struct PcPrediction {
  PcState next;
  PcJacobian F;       // ∂next/∂s
  PcNoiseJacobian G;  // ∂next/∂(l, r)
};
PcPrediction pose_calibrator_predict(const PcState& s, double dphi_left_rad, double dphi_right_rad);

class PoseCalibrator {
 public:
  // Throws std::invalid_argument with IsValid's message.
  explicit PoseCalibrator(const PoseCalibratorParams& params);

  // Starts (or restarts, keeping the geometry and its covariance) at a known
  // pose with the given sds; the pose's correlation with the geometry is
  // dropped.
  void start_at(const PlanarPose& pose, double sd_xy_m, double sd_theta_rad);
  // Starts (or restarts, keeping the geometry) with the pose unknown: it is
  // acquired from the fixes to come.
  void start_from_fixes();

  // Throws std::invalid_argument for a sample that breaks its contract.
  const CalibEstimate& step(const PoseCalibSample& sample);

  const CalibEstimate& estimate() const { return estimate_; }
  // False while the pose is still being acquired from the fixes.
  bool pose_known() const { return pose_known_; }
  PlanarPose pose() const { return {x_(kPcX), x_(kPcY), x_(kPcTheta)}; }
  const PcCov& covariance() const { return P_; }
  long iterations() const { return iteration_; }
  long fixes_applied() const { return fixes_applied_; }
  long fixes_rejected() const { return fixes_rejected_; }
  long reacquisitions() const { return reacquisitions_; }
  // log p(fix | past) of the last step's fix (0 without one, and while the
  // pose is acquired): odotune/filters/memory_pair.h's change test.
  double last_log_predictive() const { return last_log_predictive_; }
  void set_memory(const DistanceMemoryParams& p) { memory_ = distance_memory(p); }
  double memory_m() const { return memory_.memory_s(); }

 private:
  void predict(const PoseCalibSample& s);
  void fix_update(const PoseCalibSample& s);
  void acquire(const PoseCalibSample& s);
  // Starts at the acquisition's first pose and re-runs its samples.
  void replay_from(const PlanarPose& start, double sd_xy_m, double sd_theta_rad);
  void fade(double rolled_m);
  // EvidenceMemory's clock, advanced here by metres rolled instead of seconds.
  static EvidenceMemory distance_memory(const DistanceMemoryParams& p) {
    return EvidenceMemory(EvidenceMemoryParams{p.min_memory_m, p.max_memory_m});
  }
  void refresh_estimate(const PoseCalibSample& s);

  // Samples an acquisition keeps at most (about 13 MB; 33 min at 100 Hz of
  // fixes that do not spread), after which it starts over.
  static constexpr std::size_t kMaxReplaySamples = 200000;
  struct Acquisition {
    PlanarPose odometry;                   // dead-reckoned in the filter's own frame with the state's geometry
    std::vector<PoseCalibSample> samples;  // since the (re)start, for the replay
    std::vector<Eigen::Vector2d> odo, fix;
    Eigen::Vector2d fix_mean = Eigen::Vector2d::Zero();  // the fixes' mean [m]
    double fix_spread_m2 = 0.0;                          // Σ|fix − mean|² [m²]
    double var_sum = 0.0;
    double distance_m = 0.0, turn_rad = 0.0;  // rolled and turned (absolute) so far
  };

  PoseCalibratorParams params_;
  PcState x_;
  PcCov P_;
  Eigen::Vector3d geometry_var0_;
  bool pose_known_ = false;
  Acquisition acq_;
  EvidenceMemory memory_;
  double rolled_since_fix_m_ = 0.0;
  int rejected_in_row_ = 0;
  CalibEstimate estimate_;
  long iteration_ = 0, fixes_applied_ = 0, fixes_rejected_ = 0, reacquisitions_ = 0;
  double last_log_predictive_ = 0.0;
};

}  // namespace odotune::filters
