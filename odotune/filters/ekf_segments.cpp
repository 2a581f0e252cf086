#include <odotune/filters/ekf_segments.h>

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

SegmentMoments reduce_segment(std::span<const WheelTravel> steps, std::span<const double> abs_yaw_rate_rad_s,
                              double wheel_base_m, std::span<double> path_x, std::span<double> path_y) {
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

namespace {

// Closed forms below (instead of generic 3 × 3 products): this runs once per
// segment and noise setting inside the tuner's loop.

// F·P·Fᵀ for F = [[1, 0, a], [0, 1, b], [0, 0, 1]], on the unique entries.
Sym3 propagate(const Sym3& P, double a, double b) {
  Sym3 o;
  o[kXX] = P[kXX] + 2.0 * a * P[kXT] + a * a * P[kTT];
  o[kXY] = P[kXY] + a * P[kYT] + b * P[kXT] + a * b * P[kTT];
  o[kXT] = P[kXT] + a * P[kTT];
  o[kYY] = P[kYY] + 2.0 * b * P[kYT] + b * b * P[kTT];
  o[kYT] = P[kYT] + b * P[kTT];
  o[kTT] = P[kTT];
  return o;
}

// out += T·S·Tᵀ for T = blkdiag(Rot(θ), 1), Rot = [[c, −s], [s, c]].
void add_rotated(Sym3& out, const Sym3& S, double c, double s) {
  const double cc = c * c, ss = s * s, cs = c * s;
  out[kXX] += cc * S[kXX] - 2.0 * cs * S[kXY] + ss * S[kYY];
  out[kXY] += cs * (S[kXX] - S[kYY]) + (cc - ss) * S[kXY];
  out[kYY] += ss * S[kXX] + 2.0 * cs * S[kXY] + cc * S[kYY];
  out[kXT] += c * S[kXT] - s * S[kYT];
  out[kYT] += s * S[kXT] + c * S[kYT];
  out[kTT] += S[kTT];
}

Sym3 to_sym(const StateCov& P) {
  return {P(kX, kX), P(kX, kY), P(kX, kTheta), P(kY, kY), P(kY, kTheta), P(kTheta, kTheta)};
}

// The predicted covariance; c, s = cos θ_u, sin θ_u.
Sym3 predict_sym(const NoiseParams& noise, const SegmentMoments& m, double c, double s, const Sym3& P) {
  // World-frame displacement over the segment, Rot(θ_u)·o_end.
  const double ex = c * m.end_x_m - s * m.end_y_m;
  const double ey = s * m.end_x_m + c * m.end_y_m;
  Sym3 Pp = propagate(P, -ey, ex);

  if (noise.model == NoiseModel::rq) {
    // Σ = Σ_j F_{end:j}·diag(r_x, r_y, r_θ)·F_{end:j}ᵀ in the world frame:
    // [[n·r_x + r_θ·(J·S2w·Jᵀ)_xx, …, r_θ·(J·S1w)_x], …, n·r_θ], with
    // S1w = Rot·S1, S2w = Rot·S2·Rotᵀ, J·M·Jᵀ = [[M_yy, −M_xy], [−M_xy, M_xx]].
    const double n = m.steps;
    const double rt = noise.r_theta_rad2;
    Sym3 S2{m.s2_xx, m.s2_xy, 0.0, m.s2_yy, 0.0, 0.0};
    Sym3 S2w{};
    add_rotated(S2w, S2, c, s);
    const double s1x = c * m.s1_x - s * m.s1_y;
    const double s1y = s * m.s1_x + c * m.s1_y;
    Pp[kXX] += n * noise.r_x_m2 + rt * S2w[kYY];
    Pp[kYY] += n * noise.r_y_m2 + rt * S2w[kXX];
    Pp[kXY] -= rt * S2w[kXY];
    Pp[kXT] -= rt * s1y;
    Pp[kYT] += rt * s1x;
    Pp[kTT] += n * rt;
    return Pp;
  }
  Sym3 sigma{};
  axpy(sigma, noise.a1 * noise.a1, m.A[0]);
  axpy(sigma, 2.0 * noise.a1 * noise.b1, m.A[1]);
  axpy(sigma, noise.b1 * noise.b1, m.A[2]);
  axpy(sigma, noise.a2 * noise.a2, m.B[0]);
  axpy(sigma, 2.0 * noise.a2 * noise.b2, m.B[1]);
  axpy(sigma, noise.b2 * noise.b2, m.B[2]);
  add_rotated(Pp, sigma, c, s);
  return Pp;
}

}  // namespace

StateCov predict_segment_cov(const NoiseParams& noise, const SegmentMoments& m, double theta_u_rad,
                             const StateCov& P) {
  return to_matrix(predict_sym(noise, m, std::cos(theta_u_rad), std::sin(theta_u_rad), to_sym(P)));
}

Divergence advance_segment(const NoiseParams& noise, const SegmentMoments& m, const Position& z, Pose* pose,
                           StateCov* P) {
  Sym3 Ps = to_sym(*P);
  const Divergence d = advance_segment(noise, m, z, std::cos((*pose)(kTheta)), std::sin((*pose)(kTheta)), pose,
                                       &Ps);
  *P = to_matrix(Ps);
  return d;
}

Divergence advance_segment(const NoiseParams& noise, const SegmentMoments& m, const Position& z,
                           double cos_theta, double sin_theta, Pose* pose, Sym3* P) {
  return advance_segment(noise, m, z, noise.q_x_m2, noise.q_y_m2, cos_theta, sin_theta, pose, P);
}

void predict_over_segment(const NoiseParams& noise, const SegmentMoments& m, double cos_theta, double sin_theta,
                          Pose* pose, Sym3* P) {
  const double c = cos_theta, s = sin_theta;
  *P = predict_sym(noise, m, c, s, *P);
  Pose& x = *pose;
  x(kX) += c * m.end_x_m - s * m.end_y_m;
  x(kY) += s * m.end_x_m + c * m.end_y_m;
  x(kTheta) += m.end_theta_rad;
}

Divergence advance_segment(const NoiseParams& noise, const SegmentMoments& m, const Position& z, double q_x_m2,
                           double q_y_m2, double cos_theta, double sin_theta, Pose* pose, Sym3* P) {
  const double c = cos_theta, s = sin_theta;
  Sym3 Pp = predict_sym(noise, m, c, s, *P);
  Pose& x = *pose;
  x(kX) += c * m.end_x_m - s * m.end_y_m;
  x(kY) += s * m.end_x_m + c * m.end_y_m;
  x(kTheta) += m.end_theta_rad;

  // The correction, as in Ekf::update: S = H·P·Hᵀ + Q, K = P·Hᵀ·S⁻¹,
  // x += K·ν, P −= K·(H·P).
  const double s11 = Pp[kXX] + q_x_m2, s12 = Pp[kXY], s22 = Pp[kYY] + q_y_m2;
  const double inv_det = 1.0 / (s11 * s22 - s12 * s12);
  const double i11 = s22 * inv_det, i12 = -s12 * inv_det, i22 = s11 * inv_det;
  // Rows of P·Hᵀ = (P_ix, P_iy) for i = x, y, θ.
  const double hx[3] = {Pp[kXX], Pp[kXY], Pp[kXT]};
  const double hy[3] = {Pp[kXY], Pp[kYY], Pp[kYT]};
  double Kx[3], Ky[3];
  for (int i = 0; i < 3; ++i) {
    Kx[i] = hx[i] * i11 + hy[i] * i12;
    Ky[i] = hx[i] * i12 + hy[i] * i22;
  }
  const double nu_x = z(0) - x(kX), nu_y = z(1) - x(kY);
  for (int i = 0; i < 3; ++i) x(i) += Kx[i] * nu_x + Ky[i] * nu_y;
  // P_ij −= K_i·(H·P)_j = Kx_i·hx_j + Ky_i·hy_j, symmetrised.
  auto sub = [&](int i, int j) {
    return 0.5 * ((Kx[i] * hx[j] + Ky[i] * hy[j]) + (Kx[j] * hx[i] + Ky[j] * hy[i]));
  };
  Pp[kXX] -= sub(0, 0);
  Pp[kXY] -= sub(0, 1);
  Pp[kXT] -= sub(0, 2);
  Pp[kYY] -= sub(1, 1);
  Pp[kYT] -= sub(1, 2);
  Pp[kTT] -= sub(2, 2);
  *P = Pp;

  if (!std::isfinite(x(kX)) || !std::isfinite(x(kY)) || !std::isfinite(x(kTheta)))
    return Divergence::non_finite;
  for (double v : Pp)
    if (!std::isfinite(v)) return Divergence::non_finite;
  // Sylvester's criterion on the symmetric matrix.
  const double m2 = Pp[kXX] * Pp[kYY] - Pp[kXY] * Pp[kXY];
  const double det = Pp[kXX] * (Pp[kYY] * Pp[kTT] - Pp[kYT] * Pp[kYT]) -
                     Pp[kXY] * (Pp[kXY] * Pp[kTT] - Pp[kYT] * Pp[kXT]) +
                     Pp[kXT] * (Pp[kXY] * Pp[kYT] - Pp[kYY] * Pp[kXT]);
  if (!(Pp[kXX] > 0.0 && m2 > 0.0 && det > 0.0)) return Divergence::covariance_not_pd;
  return Divergence::none;
}

}  // namespace odotune::filters
