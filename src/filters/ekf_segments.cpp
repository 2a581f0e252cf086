#include "filters/ekf_segments.h"

#include <cmath>
#include <vector>

namespace odotune::filters {

namespace {

enum SymIndex : int { kXX = 0, kXY = 1, kXT = 2, kYY = 3, kYT = 4, kTT = 5 };

void add_outer(Sym3& S, double w, const Eigen::Vector3d& u) {
  S[kXX] += w * u(kX) * u(kX);
  S[kXY] += w * u(kX) * u(kY);
  S[kXT] += w * u(kX) * u(kTheta);
  S[kYY] += w * u(kY) * u(kY);
  S[kYT] += w * u(kY) * u(kTheta);
  S[kTT] += w * u(kTheta) * u(kTheta);
}

void axpy(Sym3& out, double a, const Sym3& x) {
  for (int i = 0; i < 6; ++i) out[i] += a * x[i];
}

StateCov to_matrix(const Sym3& s) {
  StateCov M;
  M << s[kXX], s[kXY], s[kXT],  //
      s[kXY], s[kYY], s[kYT],   //
      s[kXT], s[kYT], s[kTT];
  return M;
}

}  // namespace

SegmentMoments reduce_segment(std::span<const WheelTravel> steps,
                              std::span<const double> abs_yaw_rate_rad_s, double wheel_base_m,
                              std::span<double> path_x, std::span<double> path_y) {
  const std::size_t n = steps.size();
  SegmentMoments m;
  m.steps = static_cast<int>(n);

  // Pass 1: the dead-reckoned path in the segment frame, and the control
  // Jacobians Ṽ_j evaluated along it.
  std::vector<double> px(n), py(n);
  std::vector<ControlJacobian> V(n);
  Pose pose = Pose::Zero();
  for (std::size_t j = 0; j < n; ++j) {
    const MotionStep step = diff_drive_step(pose, steps[j], wheel_base_m);
    V[j] = step.V;
    pose = step.next;
    px[j] = pose(kX);
    py[j] = pose(kY);
  }
  m.end_x_m = pose(kX);
  m.end_y_m = pose(kY);
  m.end_theta_rad = pose(kTheta);
  if (!path_x.empty()) std::copy(px.begin(), px.end(), path_x.begin());
  if (!path_y.empty()) std::copy(py.begin(), py.end(), path_y.begin());

  // Pass 2: the noise injected at step j reaches the segment's end through
  // F̃_{end:j} = [[I, J·δ_j], [0, 1]], δ_j = o_end − o_j.
  for (std::size_t j = 0; j < n; ++j) {
    const double dx = m.end_x_m - px[j];
    const double dy = m.end_y_m - py[j];
    m.s1_x += dx;
    m.s1_y += dy;
    m.s2_xx += dx * dx;
    m.s2_xy += dx * dy;
    m.s2_yy += dy * dy;

    auto propagate = [&](const Eigen::Vector3d& v) {
      return Eigen::Vector3d(v(kX) - dy * v(kTheta), v(kY) + dx * v(kTheta), v(kTheta));
    };
    const Eigen::Vector3d ul = propagate(V[j].col(kLeft));
    const Eigen::Vector3d ur = propagate(V[j].col(kRight));
    const double l = steps[j].left_m, r = steps[j].right_m, diff = l - r;
    const double w = abs_yaw_rate_rad_s[j];
    double wp = 1.0;  // |ω|^p
    for (int p = 0; p < 3; ++p) {
      add_outer(m.A[p], wp * l * l, ul);
      add_outer(m.A[p], wp * r * r, ur);
      add_outer(m.B[p], wp * diff * diff, ul);
      add_outer(m.B[p], wp * diff * diff, ur);
      wp *= w;
    }
  }
  return m;
}

StateCov predict_segment_cov(const NoiseParams& noise, const SegmentMoments& m, double theta_u_rad,
                             const StateCov& P) {
  const double c = std::cos(theta_u_rad), s = std::sin(theta_u_rad);
  // World-frame displacement over the segment, Rot(θ_u)·o_end.
  const double ex = c * m.end_x_m - s * m.end_y_m;
  const double ey = s * m.end_x_m + c * m.end_y_m;
  StateCov F = StateCov::Identity();
  F(kX, kTheta) = -ey;
  F(kY, kTheta) = ex;
  StateCov Pp = F * P * F.transpose();

  if (noise.model == NoiseModel::rq) {
    // Σ = Σ_j F_{end:j}·diag(r_x, r_y, r_θ)·F_{end:j}ᵀ in the world frame, with
    // world δ_j = Rot·δ̃_j: S1w = Rot·S1, S2w = Rot·S2·Rotᵀ.
    const double n = m.steps;
    const double s1x = c * m.s1_x - s * m.s1_y;
    const double s1y = s * m.s1_x + c * m.s1_y;
    Eigen::Matrix2d S2;
    S2 << m.s2_xx, m.s2_xy, m.s2_xy, m.s2_yy;
    Eigen::Matrix2d Rot;
    Rot << c, -s, s, c;
    const Eigen::Matrix2d S2w = Rot * S2 * Rot.transpose();
    const double rt = noise.r_theta_rad2;
    // J·M·Jᵀ = [[M_yy, −M_xy], [−M_xy, M_xx]],  J·S1 = (−S1_y, S1_x).
    Pp(kX, kX) += n * noise.r_x_m2 + rt * S2w(1, 1);
    Pp(kY, kY) += n * noise.r_y_m2 + rt * S2w(0, 0);
    Pp(kX, kY) -= rt * S2w(0, 1);
    Pp(kY, kX) -= rt * S2w(0, 1);
    Pp(kX, kTheta) -= rt * s1y;
    Pp(kTheta, kX) -= rt * s1y;
    Pp(kY, kTheta) += rt * s1x;
    Pp(kTheta, kY) += rt * s1x;
    Pp(kTheta, kTheta) += n * rt;
    return Pp;
  }

  Sym3 sigma{};
  axpy(sigma, noise.a1 * noise.a1, m.A[0]);
  axpy(sigma, 2.0 * noise.a1 * noise.b1, m.A[1]);
  axpy(sigma, noise.b1 * noise.b1, m.A[2]);
  axpy(sigma, noise.a2 * noise.a2, m.B[0]);
  axpy(sigma, 2.0 * noise.a2 * noise.b2, m.B[1]);
  axpy(sigma, noise.b2 * noise.b2, m.B[2]);
  StateCov T = StateCov::Identity();
  T(kX, kX) = c;
  T(kX, kY) = -s;
  T(kY, kX) = s;
  T(kY, kY) = c;
  Pp += T * to_matrix(sigma) * T.transpose();
  return Pp;
}

Divergence advance_segment(const NoiseParams& noise, const SegmentMoments& m, const Position& z,
                           Pose* pose, StateCov* P) {
  const double theta_u = (*pose)(kTheta);
  const double c = std::cos(theta_u), s = std::sin(theta_u);
  StateCov Pp = predict_segment_cov(noise, m, theta_u, *P);
  Pose x = *pose;
  x(kX) += c * m.end_x_m - s * m.end_y_m;
  x(kY) += s * m.end_x_m + c * m.end_y_m;
  x(kTheta) += m.end_theta_rad;

  // The correction, as in Ekf::update.
  const Eigen::Matrix2d S =
      Pp.topLeftCorner<2, 2>() + Eigen::Vector2d(noise.q_x_m2, noise.q_y_m2).asDiagonal().toDenseMatrix();
  const Eigen::Matrix<double, kStateDim, 2> PHt = Pp.leftCols<2>();
  const Eigen::Matrix<double, kStateDim, 2> K = PHt * S.inverse();
  x += K * (z - x.head<2>());
  Pp -= K * PHt.transpose();
  Pp = 0.5 * (Pp + Pp.transpose()).eval();
  *pose = x;
  *P = Pp;
  if (!x.allFinite() || !Pp.allFinite()) return Divergence::non_finite;
  if (!is_positive_definite(Pp)) return Divergence::covariance_not_pd;
  return Divergence::none;
}

}  // namespace odotune::filters
