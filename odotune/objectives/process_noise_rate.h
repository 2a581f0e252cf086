// The constant process-noise *rate* that stands for odotune's per-step process
// noise R over recorded tracks: what `odotune export --format
// robot_localization` writes into robot_localization's
// process_noise_covariance (a variance per second, see odotune/results/ros_export.h).
//
// odotune adds R_k once per odometry step k (odotune/filters/ekf_noise.h):
//   rq:          R_k = diag(r_x, r_y, r_θ), the same at every step;
//   alpha, gyro: R_k = V_k·diag(σl², σr²)·V_kᵀ (Kovacs et al. eq. 3–5; α1, α2
//                from eq. 6–7 with the step's |ω_z| for gyro), which depends
//                on the step's wheel travel, on |ω_z| and — through the control
//                Jacobian V_k, evaluated at the filter's heading — on θ.
// A filter with a constant Q per second has no such dependence, so the
// equivalent used here is the time average over the given tracks:
//
//   Q_ii = Σ_tracks Σ_{k=2..N} R_k[i][i]  /  Σ_tracks (t_N − t_1),   i ∈ {x, y, θ}
//
// where, on each track, k runs over its odometry steps in time order and t_k
// is the time [s] of the odometry sample that ends step k. Step 1 is left
// out because its start (the odometry sample before it, possibly before the
// filter's start row) is not part of the replay input; steps 2..N cover
// exactly [t_1, t_N]. R_k is the matrix the tuned filter itself adds on that
// step: the EKF is replayed on the track with the tuned noise (prediction
// and position-fix correction, as in replay_ekf), and V_k is taken at its
// estimated heading before the step (what Ekf::predict uses). Only the
// diagonal (x, y, θ) is kept; R's off-diagonal terms are dropped.
//
// Heading dependence: in the world frame R_k puts the along-track and the
// across-track wheel noise on x and y according to θ, so the average holds
// for motion like the tracks' (its mix of headings, speeds and turns); it is
// not a property of the robot alone. For rq the average is exactly
// r × odometry_rate_hz, i.e. ros_input_from_rq's conversion.
//
// Units: R is SI (m², rad²) per step; the result is m²/s and rad²/s.
#pragma once

#include <span>

#include <odotune/filters/ekf_noise.h>
#include <odotune/objectives/replay_input.h>

namespace odotune::objectives {

struct ProcessNoiseRate {
  double x_m2_per_s = 0.0;        // Q_xx
  double y_m2_per_s = 0.0;        // Q_yy
  double theta_rad2_per_s = 0.0;  // Q_θθ
  // Steps counted / duration_s: the mean odometry (= prediction) rate.
  double odometry_rate_hz = 0.0;
  long steps = 0;           // Σ (N − 1) over the tracks
  double duration_s = 0.0;  // Σ (t_N − t_1) over the tracks
};

// The mean odometry rate of the tracks, Σ (N − 1) / Σ (t_N − t_1) with N, t_k
// as above. Throws std::invalid_argument naming the track when there are no
// inputs or a track has fewer than two odometry steps.
double odometry_rate_hz(std::span<const ReplayInput> inputs);

// The time-averaged process-noise rate of `noise` over `inputs` (formula
// above). Throws std::invalid_argument for invalid noise or inputs as for
// odometry_rate_hz, and std::runtime_error naming the track and time when
// the filter diverges on a track (no meaningful average).
ProcessNoiseRate equivalent_process_noise_rate(const filters::NoiseParams& noise,
                                               std::span<const ReplayInput> inputs);

}  // namespace odotune::objectives
