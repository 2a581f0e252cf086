#include <odotune/diagnose/term_search.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>
#include <fmt/format.h>

#include <odotune/diagnose/option_rules.h>
#include <odotune/diagnose/series_interp.h>

namespace odotune::diagnose {

namespace {

using sim::TermBasis;
using sim::TermTarget;

// One candidate term of the library: its basis values per odometry interval.
struct Column {
  TermTarget target = TermTarget::v_l;
  TermBasis basis = TermBasis::speed;
  std::vector<double> f;  // basis(state) per interval [m/s per unit coef]
  double step = 0.0;      // forward-difference step of its coefficient
  // Both wheels with one coefficient: f on the left wheel (target v_l), f_right
  // (the basis of the right wheel's state) on the right.
  bool both = false;
  std::vector<double> f_right;
};

// Everything that does not depend on the coefficients.
struct Problem {
  const DiagInput& in;
  const std::vector<Window>& windows;
  const EffectModel& model;
  std::vector<double> params;
  double base_eff_m = 1.0;  // the base the body step uses (nominal D times wheel_base_error)
  double skid_k = 0.0;
  bool skid = false, heading = false;
  std::vector<Column> cols;
  std::vector<Pose<double>> anchors;  // per window (closed form at zero coefficients)
  int align_iterations = 4;
};

// The chosen model's ground travel per interval over the whole track (one
// pass; slip_zone tested on the reference position) and the state of
// model_terms.h there; then the library's columns.
void build_columns(Problem& p, int harmonics) {
  const DiagInput& in = p.in;
  const OdoSeries& s = p.model.series();
  const std::size_t n = s.t_s.size();
  std::vector<sim::TermState> st(n - 1);
  Stepper<double> stepper(p.model, p.params.data());
  stepper.start(0);
  const bool angles = in.odometry == OdometryKind::wheel_angles && !s.from_commands;
  const bool have_phi = angles || (in.radius_l_m > 0.0 && in.radius_r_m > 0.0);
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const double h = s.t_s[k + 1] - s.t_s[k], tm = 0.5 * (s.t_s[k] + s.t_s[k + 1]);
    const Pose<double> at{interp_held(in.ref_t_s, in.ref_x_m, s.t_s[k]),
                          interp_held(in.ref_t_s, in.ref_y_m, s.t_s[k]), 0.0};
    const BodyStep<double> b = stepper.step(k, at);
    sim::TermState& x = st[k];
    const double gl = b.ds - 0.5 * b.dth * p.base_eff_m, gr = b.ds + 0.5 * b.dth * p.base_eff_m;
    x.v_l = gl / h;
    x.v_r = gr / h;
    x.v = b.ds / h;
    x.w = b.dth / h;
    x.a_l = s.a_l_mps2[k];
    x.a_r = s.a_r_mps2[k];
    if (angles) {
      x.phi_l = 0.5 * (in.phi_l_rad[k] + in.phi_l_rad[k + 1]);
      x.phi_r = 0.5 * (in.phi_r_rad[k] + in.phi_r_rad[k + 1]);
    } else if (have_phi) {
      x.phi_l = 0.5 * (s.s_l_m[k] + s.s_l_m[k + 1]) / in.radius_l_m;
      x.phi_r = 0.5 * (s.s_r_m[k] + s.s_r_m[k + 1]) / in.radius_r_m;
    }
    x.x = interp_held(in.ref_t_s, in.ref_x_m, tm);
    x.y = interp_held(in.ref_t_s, in.ref_y_m, tm);
    x.t = tm - s.t_s.front();
  }
  for (TermTarget t : {TermTarget::v_l, TermTarget::v_r}) {
    double mean_speed = 0.0;
    for (const sim::TermState& x : st) mean_speed += std::abs(t == TermTarget::v_l ? x.v_l : x.v_r);
    mean_speed /= static_cast<double>(st.size());
    for (TermBasis b : sim::all_term_bases()) {
      const int k = b >= TermBasis::sin_1 && b <= TermBasis::cos_3 ? (static_cast<int>(b) + 1) / 2 : 0;
      if (k > harmonics || (k > 0 && !have_phi)) continue;
      Column c{t, b, std::vector<double>(st.size()), 0.0, false, {}};
      double sum_sq = 0.0;
      for (std::size_t i = 0; i < st.size(); ++i) {
        c.f[i] = sim::basis_value(t, b, st[i]);
        sum_sq += c.f[i] * c.f[i];
      }
      const double rms = std::sqrt(sum_sq / static_cast<double>(st.size()));
      if (!(rms > 0.0) || !std::isfinite(rms)) continue;  // nothing to fit (e.g. a robot at rest)
      c.step = std::max(mean_speed, 1e-3) / rms;          // scaled by fd_rel_step in search_terms
      p.cols.push_back(std::move(c));
    }
  }
  // The same basis on both wheels with one coefficient: the reading in which
  // the robot, not one wheel, departs from the model.
  const std::size_t singles = p.cols.size();
  for (std::size_t i = 0; i < singles; ++i) {
    if (p.cols[i].target != TermTarget::v_l) continue;
    for (std::size_t j = 0; j < singles; ++j) {
      if (p.cols[j].target != TermTarget::v_r || p.cols[j].basis != p.cols[i].basis) continue;
      Column c{TermTarget::v_l, p.cols[i].basis, p.cols[i].f, std::min(p.cols[i].step, p.cols[j].step), true,
               p.cols[j].f};
      p.cols.push_back(std::move(c));
    }
  }
}

// The column of the same basis on both wheels, for a one-wheel column; -1 if none.
int both_wheels_column(const Problem& p, int j) {
  const Column& c = p.cols[static_cast<std::size_t>(j)];
  if (c.both) return -1;
  for (std::size_t k = 0; k < p.cols.size(); ++k)
    if (p.cols[k].both && p.cols[k].basis == c.basis) return static_cast<int>(k);
  return -1;
}

// Travel corrections per interval [m/s] of both wheels for coefficients c
// (one per column; zeros skipped).
struct Corrections {
  std::vector<double> l, r;
};
Corrections corrections(const Problem& p, const Eigen::VectorXd& c) {
  const std::size_t n = p.model.series().t_s.size() - 1;
  Corrections out{std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)};
  for (std::size_t j = 0; j < p.cols.size(); ++j) {
    if (c(static_cast<Eigen::Index>(j)) == 0.0) continue;
    const double cj = c(static_cast<Eigen::Index>(j));
    std::vector<double>& dst = p.cols[j].target == TermTarget::v_l ? out.l : out.r;
    for (std::size_t k = 0; k < n; ++k) dst[k] += cj * p.cols[j].f[k];
    if (p.cols[j].both)
      for (std::size_t k = 0; k < n; ++k) out.r[k] += cj * p.cols[j].f_right[k];
  }
  return out;
}

// Dead reckoning of window w from its anchor with the chosen model plus the
// corrections (as replay_window of window_replay.h), then the anchor's
// Gauss-Newton re-alignment; the window's residuals in sigmas (file comment
// of term_search.h): per scored sample dx, dy (and dθ).
Eigen::VectorXd window_residuals(const Problem& p, const Window& w, const Corrections& corr, bool free) {
  const DiagInput& in = p.in;
  const auto& t = p.model.series().t_s;
  const std::size_t m = w.ref_end - w.ref_begin;
  std::vector<Pose<double>> pred(m);
  Stepper<double> stepper(p.model, p.params.data());
  stepper.start(w.node_begin);
  Pose<double> pose = free ? p.anchors[static_cast<std::size_t>(w.index)] : reference_pose_at(in, w.t_begin_s);
  std::size_t r = w.ref_begin;
  while (r < w.ref_end && in.ref_t_s[r] <= t[w.node_begin]) pred[r++ - w.ref_begin] = pose;
  for (std::size_t k = w.node_begin; k < w.node_end && r < w.ref_end; ++k) {
    const Pose<double> prev = pose;
    BodyStep<double> b = stepper.step(k, prev);
    const double h = t[k + 1] - t[k];
    if (corr.l[k] != 0.0 || corr.r[k] != 0.0) {
      const double gl = b.ds - 0.5 * b.dth * p.base_eff_m + h * corr.l[k];
      const double gr = b.ds + 0.5 * b.dth * p.base_eff_m + h * corr.r[k];
      b.ds = 0.5 * (gl + gr);
      b.dth = (gr - gl) / p.base_eff_m;
      if (p.skid) b.dy = -p.skid_k * b.ds * b.dth / h;
    }
    advance(pose, b);
    while (r < w.ref_end && in.ref_t_s[r] <= t[k + 1]) {
      const double f = (in.ref_t_s[r] - t[k]) / h;
      pred[r++ - w.ref_begin] = {prev.x + f * (pose.x - prev.x), prev.y + f * (pose.y - prev.y),
                                 prev.th + f * (pose.th - prev.th)};
    }
  }
  while (r < w.ref_end) pred[r++ - w.ref_begin] = pose;

  const int per = p.heading ? 3 : 2;
  const double ism = 1.0 / in.ref_sigma_m, ish = p.heading ? 1.0 / in.ref_sigma_rad : 0.0;
  Eigen::VectorXd res(static_cast<Eigen::Index>(m) * per);
  for (int it = 0;; ++it) {
    double cx = 0.0, cy = 0.0;
    for (const Pose<double>& q : pred) {
      cx += q.x;
      cy += q.y;
    }
    cx /= static_cast<double>(m);
    cy /= static_cast<double>(m);
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < m; ++i) {
      const std::size_t gi = w.ref_begin + i;
      const auto row = static_cast<Eigen::Index>(i) * per;
      res(row) = (pred[i].x - in.ref_x_m[gi]) * ism;
      res(row + 1) = (pred[i].y - in.ref_y_m[gi]) * ism;
      if (p.heading) res(row + 2) = (pred[i].th - in.ref_theta_rad[gi]) * ish;
      // Derivatives by (dx, dy, dφ) of a rigid motion about the centroid.
      const Eigen::Vector3d jx(ism, 0.0, -(pred[i].y - cy) * ism), jy(0.0, ism, (pred[i].x - cx) * ism);
      A += jx * jx.transpose() + jy * jy.transpose();
      g += jx * res(row) + jy * res(row + 1);
      if (p.heading) {
        const Eigen::Vector3d jh(0.0, 0.0, ish);
        A += jh * jh.transpose();
        g += jh * res(row + 2);
      }
    }
    if (!free || it >= p.align_iterations) break;
    const Eigen::Vector3d d = -A.ldlt().solve(g);
    if (!d.allFinite()) break;
    const double c = std::cos(d(2)), s = std::sin(d(2));
    for (Pose<double>& q : pred) {
      const double ux = q.x - cx, uy = q.y - cy;
      q = {cx + c * ux - s * uy + d(0), cy + s * ux + c * uy + d(1), q.th + d(2)};
    }
  }
  return res;
}

std::vector<Eigen::VectorXd> all_residuals(const Problem& p, const std::vector<int>& which,
                                           const Eigen::VectorXd& c, bool free = true) {
  const Corrections corr = corrections(p, c);
  std::vector<Eigen::VectorXd> out;
  out.reserve(which.size());
  for (int w : which) out.push_back(window_residuals(p, p.windows[static_cast<std::size_t>(w)], corr, free));
  return out;
}

// Position RMSE [m] pooled over windows from their residuals in sigmas.
double pos_rmse(const std::vector<Eigen::VectorXd>& res, bool heading, double sigma_m) {
  const int per = heading ? 3 : 2;
  double sum = 0.0;
  long n = 0;
  for (const Eigen::VectorXd& r : res)
    for (Eigen::Index i = 0; i + 1 < r.size(); i += per, ++n) sum += r(i) * r(i) + r(i + 1) * r(i + 1);
  return n > 0 ? sigma_m * std::sqrt(sum / static_cast<double>(n)) : std::nan("");
}

// Jacobian columns `cols` of the aligned residuals of windows `which` at c
// (forward differences), one matrix per window.
std::vector<Eigen::MatrixXd> jacobians(const Problem& p, const std::vector<int>& which,
                                       const Eigen::VectorXd& c, const std::vector<Eigen::VectorXd>& r0,
                                       const std::vector<int>& cols, double rel_step) {
  std::vector<Eigen::MatrixXd> J;
  J.reserve(r0.size());
  for (const Eigen::VectorXd& r : r0) J.emplace_back(r.size(), static_cast<Eigen::Index>(cols.size()));
  for (std::size_t q = 0; q < cols.size(); ++q) {
    Eigen::VectorXd cp = c;
    const double step = rel_step * p.cols[static_cast<std::size_t>(cols[q])].step;
    cp(cols[q]) += step;
    const std::vector<Eigen::VectorXd> r1 = all_residuals(p, which, cp);
    for (std::size_t w = 0; w < which.size(); ++w)
      J[w].col(static_cast<Eigen::Index>(q)) = (r1[w] - r0[w]) / step;
  }
  return J;
}

// Normal equations of one window, in the columns' scaled units.
struct Normal {
  Eigen::MatrixXd G;
  Eigen::VectorXd b;
  double e = 0.0;
  long n = 0;
};

// Least squares on the support S from summed normal equations (small ridge).
Eigen::VectorXd solve_support(const Normal& sum, const std::vector<int>& S) {
  const auto k = static_cast<Eigen::Index>(S.size());
  Eigen::MatrixXd G(k, k);
  Eigen::VectorXd b(k);
  for (Eigen::Index i = 0; i < k; ++i) {
    b(i) = sum.b(S[static_cast<std::size_t>(i)]);
    for (Eigen::Index j = 0; j < k; ++j)
      G(i, j) = sum.G(S[static_cast<std::size_t>(i)], S[static_cast<std::size_t>(j)]);
  }
  G.diagonal().array() += 1e-9 * (G.trace() / static_cast<double>(std::max<Eigen::Index>(k, 1)) + 1e-12);
  return -G.ldlt().solve(b);
}

double sse_of(const Normal& f, const std::vector<int>& S, const Eigen::VectorXd& c) {
  double s = f.e;
  for (std::size_t i = 0; i < S.size(); ++i) {
    s += 2.0 * c(static_cast<Eigen::Index>(i)) * f.b(S[i]);
    for (std::size_t j = 0; j < S.size(); ++j)
      s += c(static_cast<Eigen::Index>(i)) * f.G(S[i], S[j]) * c(static_cast<Eigen::Index>(j));
  }
  return s;
}

// K-fold CV score of support S: pooled held-out squared error per residual.
double cv_score(const std::vector<Normal>& fold, const Normal& total, const std::vector<int>& S) {
  double sse = 0.0;
  long n = 0;
  for (const Normal& f : fold) {
    if (S.empty()) {
      sse += f.e;
    } else {
      Normal rest{total.G - f.G, total.b - f.b, total.e - f.e, total.n - f.n};
      sse += sse_of(f, S, solve_support(rest, S));
    }
    n += f.n;
  }
  return sse / static_cast<double>(std::max<long>(n, 1));
}

std::string label(const Column& c) {
  if (c.both)
    return fmt::format("both wheels: {} and {}", sim::term_name(TermTarget::v_l, c.basis),
                       sim::term_name(TermTarget::v_r, c.basis));
  return fmt::format("{}: {}", sim::target_name(c.target), sim::term_name(c.target, c.basis));
}

// What the terms depend on, in words, each once, in the order found.
std::string conditions_of(const std::vector<sim::ModelTerm>& terms) {
  std::vector<std::string> parts;
  for (const sim::ModelTerm& t : terms) {
    const std::string wheel = t.target == TermTarget::v_l ? "left" : "right";
    std::string s;
    switch (t.basis) {
      case TermBasis::speed: s = fmt::format("in proportion to the {} wheel's speed", wheel); break;
      case TermBasis::sin_1:
      case TermBasis::cos_1: s = fmt::format("periodic in the {} wheel's angle, once per turn", wheel); break;
      case TermBasis::sin_2:
      case TermBasis::cos_2: s = fmt::format("periodic in the {} wheel's angle, twice per turn", wheel); break;
      case TermBasis::sin_3:
      case TermBasis::cos_3:
        s = fmt::format("periodic in the {} wheel's angle, three times per turn", wheel);
        break;
      case TermBasis::constant: s = fmt::format("a constant offset of the {} wheel's speed", wheel); break;
      case TermBasis::accel: s = fmt::format("with the {} wheel's acceleration", wheel); break;
      case TermBasis::turn_speed: s = "in turns taken at speed (|v·w|)"; break;
      case TermBasis::speed_turn: s = fmt::format("while turning, with the {} wheel's speed", wheel); break;
      case TermBasis::speed_sq:
        s = fmt::format("growing with the square of the {} wheel's speed", wheel);
        break;
      case TermBasis::speed_time: s = "changing with time"; break;
      case TermBasis::speed_x:
      case TermBasis::speed_y: s = "depending on the position"; break;
    }
    if (std::find(parts.begin(), parts.end(), s) == parts.end()) parts.push_back(s);
  }
  std::string out;
  for (const std::string& s : parts) out += (out.empty() ? "" : "; ") + s;
  return out;
}

// The wheel effects of `chosen` (term search ignores gyro effects).
EffectSet wheel_only(const EffectSet& chosen) {
  EffectSet wheel = chosen;
  wheel.disable(Effect::gyro_bias).disable(Effect::gyro_scale);
  return wheel;
}

// The problem of `in` cut into `windows` with the chosen model and the
// library's columns (`in`, `windows` and `model` must outlive it).
Problem make_problem(const DiagInput& in, const std::vector<Window>& windows, const EffectModel& model,
                     const EffectSet& wheel, const TermSearchOptions& o) {
  Problem p{in, windows, model, pack(wheel), 1.0, 0.0, false, false, {}, {}, 4};
  p.base_eff_m = model.series().wheel_base_m *
                 (wheel.on(Effect::wheel_base_error) ? wheel.get(Effect::wheel_base_error, "scale") : 1.0);
  p.skid = wheel.on(Effect::lateral_skid);
  p.skid_k = p.skid ? wheel.get(Effect::lateral_skid, "k") : 0.0;
  p.heading = in.has_ref_heading() && std::isfinite(in.ref_sigma_rad) && in.ref_sigma_rad > 0.0;
  p.align_iterations = o.align_iterations;
  p.anchors = replay(model, p.params, in, windows, {}, nullptr, Anchoring::free).anchors;
  build_columns(p, o.harmonics);
  return p;
}

// Throws unless every window of `train` and `heldout` exists.
void check_window_lists(const std::vector<int>& train, const std::vector<int>& heldout,
                        const std::vector<Window>& windows) {
  for (const std::vector<int>* list : {&train, &heldout})
    for (int w : *list)
      if (w < 0 || static_cast<std::size_t>(w) >= windows.size())
        throw std::invalid_argument(fmt::format("term search: window {} does not exist (the track has {})", w,
                                                windows.size()));
}

// The problem linearised at zero coefficients on the training windows, the
// columns scaled to unit norm (`scale`, 0 for a column that never moves a
// residual): normal equations per fold and in total.
struct Linearised {
  Eigen::VectorXd scale;
  std::vector<Normal> fold;
  Normal total;
};
Linearised linearise(const Problem& p, const std::vector<int>& train, const Eigen::VectorXd& zero,
                     const std::vector<Eigen::VectorXd>& r_train, const TermSearchOptions& o) {
  const auto m = static_cast<Eigen::Index>(p.cols.size());
  std::vector<int> all_cols(static_cast<std::size_t>(m));
  for (Eigen::Index j = 0; j < m; ++j) all_cols[static_cast<std::size_t>(j)] = static_cast<int>(j);
  std::vector<Eigen::MatrixXd> J = jacobians(p, train, zero, r_train, all_cols, o.fd_rel_step);
  Eigen::VectorXd scale = Eigen::VectorXd::Zero(m);
  for (const Eigen::MatrixXd& Jw : J) scale += Jw.colwise().squaredNorm().transpose();
  for (Eigen::Index j = 0; j < m; ++j) scale(j) = scale(j) > 0.0 ? 1.0 / std::sqrt(scale(j)) : 0.0;
  const int K = std::min<int>(o.folds, static_cast<int>(train.size()));
  std::vector<Normal> fold(static_cast<std::size_t>(K),
                           Normal{Eigen::MatrixXd::Zero(m, m), Eigen::VectorXd::Zero(m), 0.0, 0});
  Normal total{Eigen::MatrixXd::Zero(m, m), Eigen::VectorXd::Zero(m), 0.0, 0};
  for (std::size_t w = 0; w < train.size(); ++w) {
    const Eigen::MatrixXd Js = J[w] * scale.asDiagonal();
    Normal& f = fold[w * static_cast<std::size_t>(K) / train.size()];
    f.G += Js.transpose() * Js, f.b += Js.transpose() * r_train[w];
    f.e += r_train[w].squaredNorm();
    f.n += r_train[w].size();
  }
  for (const Normal& f : fold) {
    total.G += f.G;
    total.b += f.b;
    total.e += f.e;
    total.n += f.n;
  }
  return {std::move(scale), std::move(fold), std::move(total)};
}

// Forward stepwise selection by CV: the support, each step in `steps`.
std::vector<int> forward_select(const Problem& p, const Linearised& lin, const TermSearchOptions& o,
                                std::vector<TermStep>& steps) {
  const auto m = static_cast<int>(p.cols.size());
  const std::vector<Normal>& fold = lin.fold;
  const Normal& total = lin.total;
  const Eigen::VectorXd& scale = lin.scale;
  std::vector<int> S;
  double current = cv_score(fold, total, S);
  steps.push_back({0, "", current, true});
  for (int step = 1; step <= o.max_terms; ++step) {
    int best = -1;
    double best_cv = 0.0;
    for (int j = 0; j < m; ++j) {
      if (scale(j) == 0.0 || std::find(S.begin(), S.end(), j) != S.end()) continue;
      std::vector<int> T = S;
      T.push_back(j);
      const double cv = cv_score(fold, total, T);
      if (best < 0 || cv < best_cv) {
        best = j;
        best_cv = cv;
      }
    }
    if (best < 0) break;
    // A term on one wheel needs evidence that the wheels differ: it must beat
    // the same term on both wheels as clearly as a term must beat none.
    const int pair = both_wheels_column(p, best);
    if (pair >= 0 && scale(pair) != 0.0 && std::find(S.begin(), S.end(), pair) == S.end()) {
      std::vector<int> T = S;
      T.push_back(pair);
      const double pair_cv = cv_score(fold, total, T);
      if (!(best_cv <= pair_cv * (1.0 - o.min_rel_cv_gain))) {
        best = pair;
        best_cv = pair_cv;
      }
    }
    const bool accept = best_cv <= current * (1.0 - o.min_rel_cv_gain);
    steps.push_back({step, label(p.cols[static_cast<std::size_t>(best)]), best_cv, accept});
    if (!accept) break;
    S.push_back(best);
    current = best_cv;
  }
  return S;
}

// The support's coefficients fitted on all training windows, with J'J and
// the residuals at them.
struct SupportFit {
  Eigen::VectorXd c;
  Eigen::MatrixXd JtJ;
  std::vector<Eigen::VectorXd> r;
};

// Final fit of the support S on all training windows: the linear solution,
// then Gauss-Newton through the replay.
SupportFit fit_support(const Problem& p, const std::vector<int>& train, const std::vector<int>& S,
                       const Linearised& lin, const Eigen::VectorXd& zero, const TermSearchOptions& o) {
  SupportFit fit;
  Eigen::VectorXd& c = fit.c;
  Eigen::MatrixXd& JtJ = fit.JtJ;
  std::vector<Eigen::VectorXd>& r = fit.r;
  c = zero;
  const Eigen::VectorXd cs = solve_support(lin.total, S);
  for (std::size_t i = 0; i < S.size(); ++i) c(S[i]) = cs(static_cast<Eigen::Index>(i)) * lin.scale(S[i]);
  r = all_residuals(p, train, c);
  for (int it = 0; it <= o.refine_iterations; ++it) {
    const std::vector<Eigen::MatrixXd> Js = jacobians(p, train, c, r, S, o.fd_rel_step);
    const auto k = static_cast<Eigen::Index>(S.size());
    JtJ = Eigen::MatrixXd::Zero(k, k);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(k);
    for (std::size_t w = 0; w < train.size(); ++w)
      JtJ += Js[w].transpose() * Js[w], g += Js[w].transpose() * r[w];
    if (it == o.refine_iterations) break;
    const Eigen::VectorXd d = -JtJ.ldlt().solve(g);
    if (!d.allFinite()) break;
    for (std::size_t i = 0; i < S.size(); ++i) c(S[i]) += d(static_cast<Eigen::Index>(i));
    r = all_residuals(p, train, c);
  }
  return fit;
}

// The fitted coefficients' covariance: (J'J)^-1 times the residual variance
// (3 anchor degrees of freedom per training window).
Eigen::MatrixXd coefficient_covariance(const SupportFit& fit, std::size_t support_size, std::size_t n_train) {
  double sse = 0.0;
  long n_res = 0;
  for (const Eigen::VectorXd& rw : fit.r) {
    sse += rw.squaredNorm();
    n_res += rw.size();
  }
  const double dof = static_cast<double>(n_res) - static_cast<double>(support_size) -
                     3.0 * static_cast<double>(n_train);
  const double s2 = dof > 0.0 ? sse / dof : std::nan("");
  const Eigen::MatrixXd& JtJ = fit.JtJ;
  return JtJ.ldlt().solve(Eigen::MatrixXd::Identity(JtJ.rows(), JtJ.cols())) * s2;
}

// The support's terms (a both-wheels column gives one per wheel), each also
// in out.model.terms with its name and standard error.
std::vector<sim::ModelTerm> support_terms(const Problem& p, const std::vector<int>& S, const Eigen::VectorXd& c,
                                          const Eigen::MatrixXd& cov, TermSearchResult& out) {
  std::vector<sim::ModelTerm> terms;
  for (std::size_t i = 0; i < S.size(); ++i) {
    const Column& col = p.cols[static_cast<std::size_t>(S[i])];
    const double se = std::sqrt(cov(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i)));
    for (TermTarget t : {col.target, TermTarget::v_r}) {
      terms.push_back({t, col.basis, c(S[i])});
      out.model.terms.push_back({terms.back(), sim::term_name(t, col.basis),
                                 std::isfinite(se) ? se : std::nan("")});
      if (!col.both) break;
    }
  }
  return terms;
}

// Found when the held-out gain clears the floor; else the reason why not.
void judge_heldout(TermSearchResult& out, const std::vector<int>& heldout, double floor_m) {
  const TermScore& h = out.model.heldout;
  const double gain = h.before_pos_rmse_m - h.after_pos_rmse_m;
  if (heldout.empty()) {
    out.reason = "no held-out window to prove the terms on";
  } else if (!(std::isfinite(gain) && gain >= floor_m && gain > 0.0)) {
    out.reason = fmt::format(
        "held-out position error {:.4f} m -> {:.4f} m: the gain is below the floor of {:.4f} m",
        h.before_pos_rmse_m, h.after_pos_rmse_m, floor_m);
  } else {
    out.found = true;
  }
}

}  // namespace

bool TermSearchOptions::IsValid(std::string* why) const {
  return check_option_rules(
      {{max_terms >= 1 && max_terms <= 16, "max_terms", static_cast<double>(max_terms), "in [1, 16]"},
       {folds >= 2 && folds <= 20, "folds", static_cast<double>(folds), "in [2, 20]"},
       {is_fraction(min_rel_cv_gain), "min_rel_cv_gain", min_rel_cv_gain, "in [0, 1]"},
       {refine_iterations >= 0 && refine_iterations <= 10, "refine_iterations",
        static_cast<double>(refine_iterations), "in [0, 10]"},
       {align_iterations >= 0 && align_iterations <= 20, "align_iterations",
        static_cast<double>(align_iterations), "in [0, 20]"},
       {std::isfinite(fd_rel_step) && fd_rel_step > 0.0 && fd_rel_step <= 0.1, "fd_rel_step", fd_rel_step,
        "in (0, 0.1]"},
       {harmonics >= 0 && harmonics <= 3, "harmonics", static_cast<double>(harmonics), "in [0, 3]"}},
      why);
}

TermSearchResult search_terms(const DiagInput& in, const EffectSet& chosen, const std::vector<Window>& windows,
                              const std::vector<int>& train, const std::vector<int>& heldout, double floor_m,
                              const TermSearchOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument("term search: " + why);
  if (train.empty()) throw std::invalid_argument("term search: no training window");
  check_window_lists(train, heldout, windows);
  const EffectSet wheel = wheel_only(chosen);
  const EffectModel model(in, wheel);
  Problem p = make_problem(in, windows, model, wheel, o);

  TermSearchResult out;
  out.floor_m = floor_m;
  out.library_size = static_cast<int>(p.cols.size());
  const auto m = static_cast<Eigen::Index>(p.cols.size());
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(m);
  // Scores anchor as a finding's fit does (window_replay.h anchoring(in)).
  const bool score_free = anchoring(in) == Anchoring::free;
  auto score = [&](const std::vector<int>& which, const Eigen::VectorXd& c) {
    return pos_rmse(all_residuals(p, which, c, score_free), p.heading, in.ref_sigma_m);
  };
  const std::vector<Eigen::VectorXd> r_train = all_residuals(p, train, zero);
  out.model.train.before_pos_rmse_m = score(train, zero);
  out.model.heldout.before_pos_rmse_m = score(heldout, zero);
  if (m == 0) {
    out.reason = "no candidate term varies on this track";
    return out;
  }

  const Linearised lin = linearise(p, train, zero, r_train, o);
  const std::vector<int> S = forward_select(p, lin, o, out.steps);
  if (S.empty()) {
    out.reason = "no candidate term lowers the cross-validated error";
    return out;
  }

  const SupportFit fit = fit_support(p, train, S, lin, zero, o);
  const Eigen::MatrixXd cov = coefficient_covariance(fit, S.size(), train.size());
  const std::vector<sim::ModelTerm> terms = support_terms(p, S, fit.c, cov, out);
  out.model.formula = sim::term_formula(terms);
  out.model.conditions = conditions_of(terms);
  out.model.train.after_pos_rmse_m = score(train, fit.c);
  out.model.heldout.after_pos_rmse_m = score(heldout, fit.c);
  judge_heldout(out, heldout, floor_m);
  return out;
}

TermScore replay_terms(const DiagInput& in, const EffectSet& chosen, const std::vector<sim::ModelTerm>& terms,
                       double window_s, const TermSearchOptions& o) {
  const EffectSet wheel = wheel_only(chosen);
  const EffectModel model(in, wheel);
  const std::vector<Window> windows = make_windows(in, window_s);
  const Problem p = make_problem(in, windows, model, wheel, o);
  Eigen::VectorXd c = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(p.cols.size()));
  for (const sim::ModelTerm& t : terms) {
    // A basis that does not vary here (no column) adds nothing to this recording.
    for (std::size_t j = 0; j < p.cols.size(); ++j)
      if (!p.cols[j].both && p.cols[j].target == t.target && p.cols[j].basis == t.basis)
        c(static_cast<Eigen::Index>(j)) = t.coef;
  }
  std::vector<int> all(windows.size());
  for (std::size_t w = 0; w < windows.size(); ++w) all[w] = static_cast<int>(w);
  const bool free = anchoring(in) == Anchoring::free;
  TermScore out;
  const std::vector<Eigen::VectorXd> before = all_residuals(p, all, Eigen::VectorXd::Zero(c.size()), free);
  out.before_pos_rmse_m = pos_rmse(before, p.heading, in.ref_sigma_m);
  out.after_pos_rmse_m = pos_rmse(all_residuals(p, all, c, free), p.heading, in.ref_sigma_m);
  for (const Eigen::VectorXd& r : before)
    out.samples += static_cast<std::size_t>(r.size() / (p.heading ? 3 : 2));
  return out;
}

}  // namespace odotune::diagnose
