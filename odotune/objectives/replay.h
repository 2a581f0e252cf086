// Replay of the pose EKF over a track, in two forms that compute the same
// numbers:
//  - replay_ekf(): the reference, one Ekf::predict per odometry step, with the
//    estimated trajectory kept for reports and exports;
//  - FastReplay: the segment-batched form (odotune/filters/ekf_segments.h) the tuner
//    calls millions of times. Built once per track; evaluate() is const,
//    allocation-free and safe to call from many threads at once.
#pragma once

#include <vector>

#include <odotune/filters/ekf.h>
#include <odotune/filters/ekf_segments.h>
#include <odotune/objectives/metrics.h>
#include <odotune/objectives/replay_input.h>

namespace odotune::objectives {

struct ReplayOutcome {
  ErrorMetrics metrics;
  filters::Divergence divergence = filters::Divergence::none;
};

struct TrajectoryPoint {
  double t_s;
  double x_m, y_m, theta_rad;
};

struct ReplayResult {
  ReplayOutcome outcome;
  std::vector<TrajectoryPoint> trajectory;  // at every ground-truth row (when asked for)
};

// The EKF parameters a replay of `in` uses for noise `noise`: the track's
// wheel base and first ground-truth pose, and the default initial covariance.
filters::EkfParams ekf_params_for(const ReplayInput& in, const filters::NoiseParams& noise);

// Reference replay. Throws std::invalid_argument if `noise` is invalid.
ReplayResult replay_ekf(const ReplayInput& in, const filters::NoiseParams& noise, bool keep_trajectory = false);

// The filter's pose at the start row and after every later row (odometry
// step, fix or ground truth), on the track's clock; stops at a divergence.
// For trajectories written out (odotune/results/tum.h).
std::vector<TrajectoryPoint> ekf_trajectory(const ReplayInput& in, const filters::NoiseParams& noise);

class FastReplay {
 public:
  explicit FastReplay(const ReplayInput& in);

  // Same metrics as replay_ekf(in, noise) up to floating-point rounding.
  // `noise` must be valid (the caller checks; parameter spaces only produce
  // valid ones).
  ReplayOutcome evaluate(const filters::NoiseParams& noise) const;

  const std::string& track_name() const { return name_; }
  long steps() const { return steps_; }                           // odometry steps replayed
  long samples() const { return static_cast<long>(ox_.size()); }  // error samples

 private:
  struct Segment {
    filters::SegmentMoments moments;
    filters::Position fix = filters::Position::Zero();  // applied at the end (unless last)
    double fix_var_x_m2 = 0.0, fix_var_y_m2 = 0.0;      // its own variances, NaN: the model's Q
    std::int32_t eval_begin = 0, eval_end = 0;
    bool has_fix = false;
  };
  std::string name_;
  long steps_ = 0;
  filters::Pose initial_pose_;
  filters::StateCov initial_cov_;
  std::vector<Segment> segments_;
  // Error samples, structure of arrays: dead-reckoned position in the frame
  // of its segment, and the ground truth it is compared with.
  std::vector<double> ox_, oy_, gx_, gy_;
};

}  // namespace odotune::objectives
