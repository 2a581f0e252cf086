// The pose EKF of odotune/filters/ekf.h, rewritten to advance a whole segment (the
// odometry steps between two position fixes) in O(1) per noise setting.
//
// Why this is exact. Between two fixes the EKF mean is pure dead reckoning, so
// relative to the pose (p_u, θ_u) left by the last fix, the predicted path is
// the odometry path o_j computed once in the "segment frame" (start at the
// origin, heading 0) and rotated by θ_u: p_j = p_u + Rot(θ_u)·o_j, θ_j = θ_u + φ_j.
// The motion Jacobians telescope: F_k·…·F_{j+1} = [[I, J·(p_k − p_j)], [0, 1]]
// with J = [[0, −1], [1, 0]], and V_j = blkdiag(Rot(θ_u), 1)·Ṽ_j where Ṽ_j is
// V evaluated in the segment frame. Hence the predicted covariance at the end
// of the segment is
//   P⁻ = F·P·Fᵀ + T·Σ̃·Tᵀ,   Σ̃ = Σ_j F̃_{end:j}·R̃_j·F̃_{end:j}ᵀ,
// with T = blkdiag(Rot(θ_u), 1). The noise R̃_j is linear in a handful of
// coefficient products (a1², a1·b1, b1², a2², a2·b2, b2² for the gyro model;
// r_x, r_y, r_θ for rq), so Σ̃ is a fixed linear combination of matrices that
// depend only on the odometry and are summed once per track. What remains per
// noise setting and step is evaluating the error against ground truth, a
// rotation and a norm that vectorise (see odotune/objectives/replay.h).
//
// The equivalence with the step-by-step Ekf is a test (tests/filters).
#pragma once

#include <array>
#include <span>

#include <odotune/filters/diff_drive.h>
#include <odotune/filters/ekf.h>
#include <odotune/filters/ekf_noise.h>

namespace odotune::filters {

// A symmetric 3 × 3 matrix as its 6 unique entries (xx, xy, xθ, yy, yθ, θθ).
using Sym3 = std::array<double, 6>;

// Everything the prediction over one segment depends on.
struct SegmentMoments {
  int steps = 0;                        // number of odometry steps n
  double end_x_m = 0.0, end_y_m = 0.0;  // o_end: dead-reckoned end position (segment frame)
  double end_theta_rad = 0.0;           // φ_end: dead-reckoned heading change
  // rq: S1 = Σ_j δ_j, S2 = Σ_j δ_j·δ_jᵀ with δ_j = o_end − o_j (segment frame).
  double s1_x = 0.0, s1_y = 0.0;
  double s2_xx = 0.0, s2_xy = 0.0, s2_yy = 0.0;
  // alpha/gyro: Σ̃ = a1²·A[0] + 2a1b1·A[1] + b1²·A[2] + a2²·B[0] + 2a2b2·B[1] + b2²·B[2].
  std::array<Sym3, 3> A{};
  std::array<Sym3, 3> B{};
};

// Reduces the odometry steps of one segment. `abs_yaw_rate_rad_s[j]` is the
// |ω_z| used by the gyro model at step j. When `path_x/path_y` are non-empty
// (size = steps.size()), the segment-frame position after each step is written
// there. Cost O(n); done once per track, not per noise setting.
SegmentMoments reduce_segment(std::span<const WheelTravel> steps, std::span<const double> abs_yaw_rate_rad_s,
                              double wheel_base_m, std::span<double> path_x = {},
                              std::span<double> path_y = {});

// Predicted covariance at the end of a segment that started with pose
// heading θ_u [rad] and covariance P (world frame).
StateCov predict_segment_cov(const NoiseParams& noise, const SegmentMoments& m, double theta_u_rad,
                             const StateCov& P);

// Advances (pose, P) over the segment and applies the fix z at its end, exactly
// as Ekf::predict over the steps followed by Ekf::update(z). Returns the first
// problem found (the state is then unusable).
Divergence advance_segment(const NoiseParams& noise, const SegmentMoments& m, const Position& z, Pose* pose,
                           StateCov* P);
// The same on the unique entries of P, with cos/sin of the pose's heading
// supplied by a caller that already has them (the tuner's inner loop).
Divergence advance_segment(const NoiseParams& noise, const SegmentMoments& m, const Position& z,
                           double cos_theta, double sin_theta, Pose* pose, Sym3* P);
// The same with the fix's own measurement variances [m²] (Ekf::update(z, q_x, q_y)).
Divergence advance_segment(const NoiseParams& noise, const SegmentMoments& m, const Position& z, double q_x_m2,
                           double q_y_m2, double cos_theta, double sin_theta, Pose* pose, Sym3* P);
// Advances (pose, P) over the segment without a correction, exactly as
// Ekf::predict over its steps.
void predict_over_segment(const NoiseParams& noise, const SegmentMoments& m, double cos_theta, double sin_theta,
                          Pose* pose, Sym3* P);

}  // namespace odotune::filters
