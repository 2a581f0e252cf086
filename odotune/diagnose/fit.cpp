#include <odotune/diagnose/fit.h>

#include <odotune/core/ceres_options.h>
#include <odotune/core/stopwatch.h>
#include <odotune/core/why.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <set>
#include <span>
#include <stdexcept>

#include <Eigen/Dense>
#include <ceres/ceres.h>
#include <fmt/format.h>

namespace odotune::diagnose {

namespace {

// Smallest eigenvalue of the unit-diagonal J'J, relative to the largest, for
// which the parameters count as determined (singular values 1e-5 apart).
constexpr double kMinEigenRatio = 1e-10;

// What every window's cost shares.
struct CostShared {
  const EffectModel* model = nullptr;
  const DiagInput* in = nullptr;
  std::vector<double> all;    // the flat parameter vector (fixed values live here)
  std::vector<int> free_pos;  // where block 0's entries go in `all`
  bool free_anchor = false;
  bool heading = false;  // heading residuals
  double inv_sigma_m = 1.0, inv_sigma_rad = 1.0;
  RobustLoss loss = RobustLoss::none;
  double c = 1.0;  // loss scale [sigmas]
};

// r -> sign(r)*sqrt(rho(r^2)) for the chosen loss, smooth through 0.
template <typename T>
T robustify(const T& r, RobustLoss loss, double c) {
  using std::log;
  using std::sqrt;
  const double a = std::abs(scalar(r));
  if (loss == RobustLoss::huber) {
    if (a <= c) return r;
    const T m = sqrt(2.0 * c * (a == scalar(r) ? r : -r) - c * c);
    return scalar(r) >= 0.0 ? m : -m;
  }
  if (loss == RobustLoss::cauchy) {
    if (a < 1e-3 * c) return r * (1.0 - r * r / (4.0 * c * c));
    const T m = c * sqrt(log(1.0 + r * r / (c * c)));
    return scalar(r) >= 0.0 ? m : -m;
  }
  return r;
}

class WindowCost {
 public:
  WindowCost(const CostShared* s, const Window& w, const Pose<double>& anchor)
      : s_(s), w_(w), anchor_(anchor) {}

  int num_residuals() const { return static_cast<int>((w_.ref_end - w_.ref_begin) * (s_->heading ? 3 : 2)); }

  template <typename T>
  bool operator()(T const* const* blocks, T* res) const {
    std::vector<T> p(s_->all.size());
    for (std::size_t i = 0; i < p.size(); ++i) p[i] = T(s_->all[i]);
    for (std::size_t j = 0; j < s_->free_pos.size(); ++j)
      p[static_cast<std::size_t>(s_->free_pos[j])] = blocks[0][j];
    const Pose<T> a = s_->free_anchor ? Pose<T>{blocks[1][0], blocks[1][1], blocks[1][2]}
                                      : Pose<T>{T(anchor_.x), T(anchor_.y), T(anchor_.th)};
    std::vector<Pose<T>> pred(w_.ref_end - w_.ref_begin);
    replay_window(*s_->model, p.data(), w_, a, s_->in->ref_t_s, pred.data());
    const DiagInput& in = *s_->in;
    T* r = res;
    for (std::size_t i = 0; i < pred.size(); ++i) {
      const std::size_t g = w_.ref_begin + i;
      const double ism = s_->inv_sigma_m * std::sqrt(in.ref_weight(g));  // this sample's own sigma
      *r++ = robustify(T((pred[i].x - in.ref_x_m[g]) * ism), s_->loss, s_->c);
      *r++ = robustify(T((pred[i].y - in.ref_y_m[g]) * ism), s_->loss, s_->c);
      if (s_->heading)
        *r++ = robustify(T((pred[i].th - in.ref_theta_rad[g]) * s_->inv_sigma_rad), s_->loss, s_->c);
    }
    return true;
  }

 private:
  const CostShared* s_;
  Window w_;
  Pose<double> anchor_;
};

// A free-anchor window with the anchor composed analytically: the window is
// dead-reckoned once in a local frame (origin at the anchor) with jets of
// the N effect parameters only, and each predicted pose is the anchor (+)
// the local pose, whose derivatives by the anchor (x0, y0, theta0) are those
// of a rigid motion. The same residuals as WindowCost with a free anchor,
// but the replay, which dominates, carries N instead of N + 3 derivatives.
template <int N>
class AnchorComposedCost : public ceres::CostFunction {
 public:
  AnchorComposedCost(const CostShared* s, const Window& w) : s_(s), w_(w) {
    set_num_residuals(static_cast<int>((w.ref_end - w.ref_begin) * (s->heading ? 3 : 2)));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(s->free_pos.size()));
    mutable_parameter_block_sizes()->push_back(3);
  }

  bool Evaluate(double const* const* blocks, double* res, double** jac) const override {
    const std::size_t k = s_->free_pos.size(), n = w_.ref_end - w_.ref_begin;
    const Pose<double> a{blocks[1][0], blocks[1][1], blocks[1][2]};
    const bool want_p = jac && jac[0], want_a = jac && jac[1];
    if (!want_p && !want_a) return evaluate_cost(blocks, a, res);
    if (!want_p) {
      evaluate_doubles(blocks, a, res, jac[1]);
      return true;
    }
    using J = ceres::Jet<double, N>;
    std::vector<Pose<J>> local(n);
    {
      std::vector<J> p(s_->all.size());
      for (std::size_t i = 0; i < p.size(); ++i) p[i] = J(s_->all[i]);
      for (std::size_t j = 0; j < k; ++j) {
        p[static_cast<std::size_t>(s_->free_pos[j])] = J(blocks[0][j]);
        if (want_p) p[static_cast<std::size_t>(s_->free_pos[j])].v[static_cast<int>(j)] = 1.0;
      }
      replay_window(*s_->model, p.data(), w_, Pose<J>{J(0.0), J(0.0), J(0.0)}, s_->in->ref_t_s, local.data(),
                    &a);
    }
    const double c = std::cos(a.th), sn = std::sin(a.th);
    const DiagInput& in = *s_->in;
    const int comps = s_->heading ? 3 : 2;
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t g = w_.ref_begin + i;
      const J& lx = local[i].x;
      const J& ly = local[i].y;
      // Value and derivatives (by the effect parameters, by the anchor) of each component.
      const double val[3] = {a.x + c * lx.a - sn * ly.a, a.y + sn * lx.a + c * ly.a, a.th + local[i].th.a};
      const double ref[3] = {in.ref_x_m[g], in.ref_y_m[g], s_->heading ? in.ref_theta_rad[g] : 0.0};
      const double ism = s_->inv_sigma_m * std::sqrt(in.ref_weight(g));  // this sample's own sigma
      const double inv[3] = {ism, ism, s_->inv_sigma_rad};
      const double da[3][3] = {
          {1.0, 0.0, -sn * lx.a - c * ly.a}, {0.0, 1.0, c * lx.a - sn * ly.a}, {0.0, 0.0, 1.0}};
      for (int m = 0; m < comps; ++m) {
        ceres::Jet<double, 1> u((val[m] - ref[m]) * inv[m], 0);
        const ceres::Jet<double, 1> r = robustify(u, s_->loss, s_->c);
        const std::size_t row = i * static_cast<std::size_t>(comps) + static_cast<std::size_t>(m);
        res[row] = r.a;
        const double scale = r.v[0] * inv[m];  // d r / d value
        if (want_p)
          for (std::size_t j = 0; j < k; ++j) {
            const int jj = static_cast<int>(j);
            const double d = m == 0   ? c * lx.v[jj] - sn * ly.v[jj]
                             : m == 1 ? sn * lx.v[jj] + c * ly.v[jj]
                                      : local[i].th.v[jj];
            jac[0][row * k + j] = scale * d;
          }
        if (want_a)
          for (std::size_t q = 0; q < 3; ++q) jac[1][row * 3 + q] = scale * da[m][q];
      }
    }
    return true;
  }

 private:
  // Residuals and, when jac_a is given, their derivatives by the anchor
  // (parameters held constant: the anchor's are those of a rigid motion, as
  // in Evaluate): the replay in doubles, the same arithmetic as the jets' values.
  void evaluate_doubles(double const* const* blocks, const Pose<double>& a, double* res, double* jac_a) const {
    const std::size_t n = w_.ref_end - w_.ref_begin;
    std::vector<double> p = s_->all;
    for (std::size_t j = 0; j < s_->free_pos.size(); ++j)
      p[static_cast<std::size_t>(s_->free_pos[j])] = blocks[0][j];
    std::vector<Pose<double>> local(n);
    replay_window(*s_->model, p.data(), w_, Pose<double>{0.0, 0.0, 0.0}, s_->in->ref_t_s, local.data(), &a);
    const double c = std::cos(a.th), sn = std::sin(a.th);
    const DiagInput& in = *s_->in;
    const int comps = s_->heading ? 3 : 2;
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t g = w_.ref_begin + i;
      const double lx = local[i].x, ly = local[i].y;
      const double val[3] = {a.x + c * lx - sn * ly, a.y + sn * lx + c * ly, a.th + local[i].th};
      const double ref[3] = {in.ref_x_m[g], in.ref_y_m[g], s_->heading ? in.ref_theta_rad[g] : 0.0};
      // Residual scaling: the same as Evaluate's (this sample's own sigma).
      const double ism = s_->inv_sigma_m * std::sqrt(in.ref_weight(g));
      const double inv[3] = {ism, ism, s_->inv_sigma_rad};
      const double da[3][3] = {{1.0, 0.0, -sn * lx - c * ly}, {0.0, 1.0, c * lx - sn * ly}, {0.0, 0.0, 1.0}};
      for (int m = 0; m < comps; ++m) {
        const ceres::Jet<double, 1> r = robustify(ceres::Jet<double, 1>((val[m] - ref[m]) * inv[m], 0),
                                                  s_->loss, s_->c);
        const std::size_t row = i * static_cast<std::size_t>(comps) + static_cast<std::size_t>(m);
        res[row] = r.a;
        if (jac_a)
          for (std::size_t q = 0; q < 3; ++q) jac_a[row * 3 + q] = r.v[0] * inv[m] * da[m][q];
      }
    }
  }

  // Residuals only (the solver's cost evaluations: trial steps, line
  // search): the replay in doubles, about N times cheaper than in jets
  // whose derivatives nobody reads. The last cost evaluation is remembered:
  // Ceres' projected line search evaluates the full trust-region step, and
  // then the minimizer evaluates the same point again
  // (ComputeCandidatePointAndEvaluateCost).
  bool evaluate_cost(double const* const* blocks, const Pose<double>& a, double* res) const {
    const std::size_t n = w_.ref_end - w_.ref_begin, k = s_->free_pos.size();
    std::vector<double> key(blocks[0], blocks[0] + k);
    key.insert(key.end(), blocks[1], blocks[1] + 3);
    if (key == memo_key_) {
      std::copy(memo_res_.begin(), memo_res_.end(), res);
      return true;
    }
    evaluate_doubles(blocks, a, res, nullptr);
    memo_key_ = std::move(key);
    memo_res_.assign(res, res + n * static_cast<std::size_t>(s_->heading ? 3 : 2));
    return true;
  }

  const CostShared* s_;
  Window w_;
  mutable std::vector<double> memo_key_, memo_res_;  // one problem, one thread (odotune/core/ceres_options.h)
};

template <int Stride>
ceres::CostFunction* make_cost(const CostShared* s, const Window& w, const Pose<double>& a) {
  auto* f = new ceres::DynamicAutoDiffCostFunction<WindowCost, Stride>(new WindowCost(s, w, a));
  f->AddParameterBlock(static_cast<int>(s->free_pos.size()));
  if (s->free_anchor) f->AddParameterBlock(3);
  f->SetNumResiduals(WindowCost(s, w, a).num_residuals());
  return f;
}

ceres::CostFunction* make_cost(int active, const CostShared* s, const Window& w, const Pose<double>& a) {
  const std::size_t k = s->free_pos.size();
  if (s->free_anchor && k <= 8) {
    if (k <= 2) return new AnchorComposedCost<2>(s, w);
    if (k <= 4) return new AnchorComposedCost<4>(s, w);
    return new AnchorComposedCost<8>(s, w);
  }
  if (active <= 2) return make_cost<2>(s, w, a);
  if (active <= 4) return make_cost<4>(s, w, a);
  if (active <= 6) return make_cost<6>(s, w, a);
  return make_cost<8>(s, w, a);
}

SetScore score(const ReplayResult& before, const ReplayResult& after) {
  SetScore s;
  const double nan = std::nan("");
  for (std::size_t i = 0; i < before.windows.size(); ++i)
    s.windows.push_back({before.windows[i].window, before.windows[i].pos_rmse_m, after.windows[i].pos_rmse_m,
                         before.windows[i].heading_rmse_rad, after.windows[i].heading_rmse_rad});
  const bool any = !before.windows.empty();
  s.before_pos_rmse_m = any ? before.pos_rmse_m : nan;
  s.after_pos_rmse_m = any ? after.pos_rmse_m : nan;
  s.before_heading_rmse_rad = any ? before.heading_rmse_rad : nan;
  s.after_heading_rmse_rad = any ? after.heading_rmse_rad : nan;
  return s;
}

// RMS distance of the predicted positions of one window from their centroid.
double spread(const ReplayResult& r, const Window& w) {
  double mx = 0, my = 0;
  const auto n = static_cast<double>(w.ref_end - w.ref_begin);
  for (std::size_t g = w.ref_begin; g < w.ref_end; ++g) {
    mx += r.pred_x_m[g];
    my += r.pred_y_m[g];
  }
  mx /= n;
  my /= n;
  double s = 0;
  for (std::size_t g = w.ref_begin; g < w.ref_end; ++g)
    s += (r.pred_x_m[g] - mx) * (r.pred_x_m[g] - mx) + (r.pred_y_m[g] - my) * (r.pred_y_m[g] - my);
  return std::sqrt(s / n);
}

// Whether the Jacobian at the current parameters has full column rank, judged
// on J'J scaled to a unit diagonal (so that units do not matter). Checked
// before ceres::Covariance, which would log an error on a singular problem.
bool full_rank(ceres::Problem& problem) {
  ceres::CRSMatrix j;
  if (!problem.Evaluate(ceres::Problem::EvaluateOptions(), nullptr, nullptr, nullptr, &j)) return false;
  Eigen::MatrixXd jtj = Eigen::MatrixXd::Zero(j.num_cols, j.num_cols);
  for (int r = 0; r < j.num_rows; ++r)
    for (int a = j.rows[static_cast<std::size_t>(r)]; a < j.rows[static_cast<std::size_t>(r) + 1]; ++a)
      for (int b = j.rows[static_cast<std::size_t>(r)]; b < j.rows[static_cast<std::size_t>(r) + 1]; ++b)
        jtj(j.cols[static_cast<std::size_t>(a)], j.cols[static_cast<std::size_t>(b)]) +=
            j.values[static_cast<std::size_t>(a)] * j.values[static_cast<std::size_t>(b)];
  const Eigen::VectorXd d = jtj.diagonal();
  if (!(d.array() > 0.0).all() || !d.allFinite()) return false;
  const Eigen::VectorXd inv = d.array().rsqrt();
  const Eigen::MatrixXd scaled = inv.asDiagonal() * jtj * inv.asDiagonal();
  const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(scaled).eigenvalues();
  return ev.minCoeff() > kMinEigenRatio * ev.maxCoeff();
}

// Whether options.held_effects keeps `e`'s parameters at their given values.
bool held_fixed(const FitOptions& options, Effect e) {
  return std::find(options.held_effects.begin(), options.held_effects.end(), e) != options.held_effects.end();
}

// Throws unless `model` was built for `in` and holds exactly the effects of `which`.
void check_model_matches(const EffectModel& model, const DiagInput& in, const EffectSet& which) {
  for (int e = 0; e < kNumEffects; ++e)
    if (model.structure().on(static_cast<Effect>(e)) != which.on(static_cast<Effect>(e)))
      throw std::invalid_argument(fmt::format("fit: the model holds '{}', the set to fit '{}'",
                                              model.structure().to_string(), which.to_string()));
  if (model.num_nodes() != in.odo_t_s.size())
    throw std::invalid_argument("fit: the model was built for another track");
}

// The held-out and training windows, checked against the track's `n_win`
// windows; no training windows given: every window not held out.
struct WindowSplit {
  std::set<int> held;
  std::vector<int> train;
};
WindowSplit split_windows(const std::vector<int>& train_windows, const std::vector<int>& heldout_windows,
                          int n_win, double window_s) {
  WindowSplit s;
  for (int w : heldout_windows) {
    if (w < 0 || w >= n_win)
      throw std::invalid_argument(fmt::format("held-out window {} does not exist (the track has {} "
                                              "windows of {} s)",
                                              w, n_win, window_s));
    s.held.insert(w);
  }
  for (int w : train_windows) {
    if (w < 0 || w >= n_win)
      throw std::invalid_argument(fmt::format("training window {} does not exist (the track has {} "
                                              "windows of {} s)",
                                              w, n_win, window_s));
    if (s.held.count(w))
      throw std::invalid_argument(fmt::format("window {} is both a training and a held-out window", w));
    s.train.push_back(w);
  }
  if (train_windows.empty())
    for (int w = 0; w < n_win; ++w)
      if (!s.held.count(w)) s.train.push_back(w);
  if (s.train.empty()) throw std::invalid_argument("fit: no training window");
  return s;
}

// What every window's cost shares; clamps the free entries of `init` into
// their bounds. Throws when no parameter is free.
CostShared make_shared_cost(const EffectModel& model, const DiagInput& in, const EffectSet& which,
                            const FitOptions& options, Anchoring mode, std::vector<double>& init) {
  const auto& layout = model.layout();
  CostShared sh;
  sh.model = &model;
  sh.in = &in;
  for (std::size_t i = 0; i < layout.size(); ++i)
    if (layout[i].fitted && !held_fixed(options, layout[i].effect)) {
      init[i] = std::clamp(init[i], layout[i].lower, layout[i].upper);
      sh.free_pos.push_back(static_cast<int>(i));
    }
  if (sh.free_pos.empty())
    throw std::invalid_argument(fmt::format("fit: effects '{}' have no parameter that dead "
                                            "reckoning can fit",
                                            which.to_string()));
  sh.all = init;
  sh.free_anchor = mode == Anchoring::free;
  sh.heading = in.has_ref_heading() && options.use_heading;
  sh.inv_sigma_m = 1.0 / in.ref_sigma_m;
  sh.inv_sigma_rad = sh.heading ? 1.0 / in.ref_sigma_rad : 1.0;
  sh.loss = options.loss;
  sh.c = options.loss_scale;
  return sh;
}

// The window's cost at the starting values, its free anchor fitted alone
// (a rigid pose against the window's samples converges in a few steps).
double settled_cost(const CostShared& sh, int active, const Window& w, std::vector<double>& free_values,
                    std::array<double, 3>& anchor) {
  ceres::Problem alone;
  const Pose<double> fixed = sh.free_anchor ? Pose<double>{} : reference_pose_at(*sh.in, w.t_begin_s);
  double cost = 0.0;
  if (sh.free_anchor) {
    alone.AddResidualBlock(make_cost(active, &sh, w, fixed), nullptr, free_values.data(), anchor.data());
    alone.SetParameterBlockConstant(free_values.data());
    ceres::Solver::Options so = core::deterministic_solver_options(5, core::FitTolerance::diagnosis);
    so.function_tolerance = 1e-8;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &alone, &summary);
    cost = summary.final_cost;
  } else {
    alone.AddResidualBlock(make_cost(active, &sh, w, fixed), nullptr, free_values.data());
    alone.Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
  }
  return cost;
}

// The solver's options: bounded, and with free anchors over several windows
// the anchors eliminated first (`anchors`: 3 values per window).
ceres::Solver::Options fit_solver_options(const FitOptions& options, bool free_anchor,
                                          std::span<double> anchors, std::span<double> free_values) {
  ceres::Solver::Options so = core::deterministic_solver_options(options.max_iterations,
                                                                 core::FitTolerance::diagnosis);
  // The bounds make Ceres run a projected Armijo line search on every trust
  // region step; with cubic interpolation (the default) its first trial
  // evaluates the Jacobian too, a second Jacobian per iteration. Quadratic
  // interpolation needs the cost only (the step is the same whenever the
  // full step satisfies Armijo, as it mostly does).
  so.line_search_interpolation_type = ceres::QUADRATIC;
  if (free_anchor && anchors.size() > 3) {
    // Each window's anchor meets only its own residuals: eliminate them
    // (Schur complement) and solve densely for the effect parameters; a
    // dense QR of the whole Jacobian costs O(rows * (3 windows)^2).
    so.linear_solver_type = ceres::DENSE_SCHUR;
    auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
    for (std::size_t i = 0; i < anchors.size(); i += 3) ordering->AddElementToGroup(&anchors[i], 0);
    ordering->AddElementToGroup(free_values.data(), 1);
    so.linear_solver_ordering = ordering;
  }
  return so;
}

// The free parameters' variances (their covariance's diagonal scaled by
// `s2`), NaN without standard errors; sets out.rank_deficient when the
// covariance cannot be computed.
std::vector<double> free_variances(ceres::Problem& problem, std::span<double> free_values, double s2,
                                   const FitOptions& options, FitSummary& out) {
  std::vector<double> var(free_values.size(), std::nan(""));
  if (options.standard_errors) {
    ceres::Covariance::Options co;
    co.algorithm_type = ceres::DENSE_SVD;
    co.num_threads = 1;
    ceres::Covariance cov(co);
    std::vector<std::pair<const double*, const double*>> blocks = {{free_values.data(), free_values.data()}};
    std::vector<double> c(free_values.size() * free_values.size());
    if (full_rank(problem) && cov.Compute(blocks, &problem) &&
        cov.GetCovarianceBlock(free_values.data(), free_values.data(), c.data())) {
      for (std::size_t j = 0; j < var.size(); ++j) var[j] = c[j * var.size() + j] * s2;
    } else {
      out.rank_deficient = true;
    }
  }
  return var;
}

// out.params: each parameter's start, fitted value, standard error and
// whether it ended at a bound.
void add_fitted_params(FitSummary& out, const std::vector<ParamSlot>& layout, const EffectSet& which,
                       const std::vector<double>& init, const std::vector<double>& fitted,
                       const std::vector<double>& var, const FitOptions& options) {
  const std::vector<double> orig = pack(which);
  for (std::size_t i = 0, j = 0; i < layout.size(); ++i) {
    FitParam p;
    p.name = layout[i].name;
    p.fitted = layout[i].fitted && !held_fixed(options, layout[i].effect);
    p.initial = p.fitted ? init[i] : orig[i];
    p.value = fitted[i];
    p.std_error = std::nan("");
    if (p.fitted) {
      if (std::isfinite(var[j]) && var[j] >= 0.0) p.std_error = std::sqrt(var[j]);
      const double tol = 1e-9 * (layout[i].upper - layout[i].lower);
      p.at_bound = p.value <= layout[i].lower + tol || p.value >= layout[i].upper - tol;
      ++j;
    }
    out.params.push_back(p);
  }
  if (!out.rank_deficient && options.standard_errors)
    for (const FitParam& p : out.params)
      if (p.fitted && !std::isfinite(p.std_error)) out.rank_deficient = true;
}

// The training windows the fit uses, each with its starting anchor (and,
// with options.settle_anchors, its settled cost); a window too short a
// motion for a free anchor (without a reference heading) is skipped.
void choose_windows(const CostShared& sh, int active, const std::vector<Window>& windows,
                    const std::vector<int>& train, const ReplayResult& train_before, const FitOptions& options,
                    std::vector<double>& free_values, std::vector<std::array<double, 3>>& anchors,
                    FitSummary& out) {
  const DiagInput& in = *sh.in;
  for (std::size_t i = 0; i < train.size(); ++i) {
    const Window& w = windows[static_cast<std::size_t>(train[i])];
    if (sh.free_anchor && !in.has_ref_heading() &&
        spread(train_before, w) < options.min_spread_sigmas * in.ref_sigma_m) {
      out.skipped_windows.push_back(w.index);
      continue;
    }
    out.fitted_windows.push_back(w.index);
    const Pose<double>& a = train_before.anchors[i];
    anchors.push_back({a.x, a.y, a.th});
    if (options.settle_anchors)
      out.settled_window_costs.push_back(settled_cost(sh, active, w, free_values, anchors.back()));
  }
}

// One residual block per fitted window (its free anchor a parameter block
// of its own: 3 values of `anchors`), and the free parameters' bounds.
void add_residual_blocks(ceres::Problem& problem, const CostShared& sh, int active,
                         const std::vector<Window>& windows, std::span<double> free_values,
                         std::span<double> anchors, FitSummary& out) {
  const DiagInput& in = *sh.in;
  const auto& layout = sh.model->layout();
  for (std::size_t i = 0; i < out.fitted_windows.size(); ++i) {
    const Window& w = windows[static_cast<std::size_t>(out.fitted_windows[i])];
    const Pose<double> a = sh.free_anchor ? Pose<double>{anchors[3 * i], anchors[3 * i + 1], anchors[3 * i + 2]}
                                          : reference_pose_at(in, w.t_begin_s);
    ceres::CostFunction* cost = make_cost(active, &sh, w, a);
    if (sh.free_anchor)
      problem.AddResidualBlock(cost, nullptr, free_values.data(), &anchors[3 * i]);
    else
      problem.AddResidualBlock(cost, nullptr, free_values.data());
    out.num_residuals += static_cast<std::size_t>(cost->num_residuals());
  }
  for (std::size_t j = 0; j < sh.free_pos.size(); ++j) {
    const ParamSlot& s = layout[static_cast<std::size_t>(sh.free_pos[j])];
    problem.SetParameterLowerBound(free_values.data(), static_cast<int>(j), s.lower);
    problem.SetParameterUpperBound(free_values.data(), static_cast<int>(j), s.upper);
  }
}

// The fit's train and held-out scores: the fitted values against the start
// (or options.score_before_at).
void score_fit(const EffectModel& model, const DiagInput& in, const std::vector<Window>& windows,
               const std::vector<int>& train, const std::set<int>& held, const ReplayResult& train_before,
               const std::vector<double>& init, const std::vector<double>& fitted, Anchoring mode,
               const FitOptions& options, FitSummary& out) {
  const std::vector<double> before = options.score_before_at ? pack(*options.score_before_at) : init;
  out.train = score(options.score_before_at ? replay(model, before, in, windows, train, nullptr, mode)
                                            : train_before,
                    replay(model, fitted, in, windows, train, nullptr, mode));
  std::vector<int> ho(held.begin(), held.end());
  if (!ho.empty())
    out.heldout = score(replay(model, before, in, windows, ho, nullptr, mode),
                        replay(model, fitted, in, windows, ho, nullptr, mode));
  else
    out.heldout = score(ReplayResult{}, ReplayResult{});
}

}  // namespace

bool FitOptions::IsValid(std::string* why) const {
  if (!(std::isfinite(window_s) && window_s >= 0.0))
    return core::invalid(why,
                         fmt::format("window_s = {}; expected a number >= 0 s (0 = one window)", window_s));
  if (!(std::isfinite(loss_scale) && loss_scale > 0.0))
    return core::invalid(why,
                         fmt::format("loss_scale = {}; expected a number > 0 (reference sigmas)", loss_scale));
  if (max_iterations < 1 || max_iterations > 100000)
    return core::invalid(why, fmt::format("max_iterations = {}; expected 1 to 100000", max_iterations));
  if (!(std::isfinite(min_spread_sigmas) && min_spread_sigmas >= 0.0))
    return core::invalid(why, fmt::format("min_spread_sigmas = {}; expected a number >= 0", min_spread_sigmas));
  std::string w;
  if (!model.IsValid(&w)) return core::invalid(why, "model: " + w);
  return true;
}

FitSummary fit_effects(const DiagInput& in, const EffectSet& which, const std::vector<int>& train_windows,
                       const std::vector<int>& heldout_windows, const FitOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("fit options: " + why);
  const EffectModel model(in, which, options.model);
  return fit_effects(model, in, which, train_windows, heldout_windows, options);
}

FitSummary fit_effects(const EffectModel& model, const DiagInput& in, const EffectSet& which,
                       const std::vector<int>& train_windows, const std::vector<int>& heldout_windows,
                       const FitOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("fit options: " + why);
  check_model_matches(model, in, which);
  const auto t_start = std::chrono::steady_clock::now();
  const std::vector<Window> windows = make_windows(in, options.window_s);
  const int n_win = static_cast<int>(windows.size());
  const WindowSplit split = split_windows(train_windows, heldout_windows, n_win, options.window_s);
  const std::set<int>& held = split.held;
  const std::vector<int>& train = split.train;

  const auto& layout = model.layout();
  std::vector<double> init = pack(which);
  const Anchoring mode = fit_anchoring(in, options);
  const CostShared sh = make_shared_cost(model, in, which, options, mode, init);

  FitSummary out;
  const ReplayResult train_before = replay(model, init, in, windows, train, nullptr, mode);
  std::vector<double> free_values;
  for (int p : sh.free_pos) free_values.push_back(init[static_cast<std::size_t>(p)]);
  std::vector<std::array<double, 3>> anchors;

  ceres::Problem problem;
  const int active = static_cast<int>(sh.free_pos.size()) + (sh.free_anchor ? 3 : 0);
  choose_windows(sh, active, windows, train, train_before, options, free_values, anchors, out);
  if (out.fitted_windows.empty())
    throw std::invalid_argument("fit: every training window is too short a motion to fit");
  // ceres::Covariance orders blocks by address: one buffer, so the same numbers with any thread count.
  std::vector<double> blocks = free_values;
  for (const auto& a : anchors) blocks.insert(blocks.end(), a.begin(), a.end());
  const std::span<double> values = std::span<double>(blocks).first(free_values.size()),
                          anchor_values = std::span<double>(blocks).subspan(free_values.size());
  add_residual_blocks(problem, sh, active, windows, values, anchor_values, out);
  const ceres::Solver::Options so = fit_solver_options(options, sh.free_anchor, anchor_values, values);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  out.converged = summary.termination_type == ceres::CONVERGENCE;
  out.termination = summary.BriefReport();
  out.iterations = static_cast<int>(summary.iterations.size()) - 1;
  out.initial_cost = summary.initial_cost;
  out.final_cost = summary.final_cost;
  const double dof = static_cast<double>(out.num_residuals) -
                     static_cast<double>(free_values.size() + 3 * (sh.free_anchor ? anchors.size() : 0));
  const double s2 = dof > 0.0 ? 2.0 * summary.final_cost / dof : std::nan("");
  out.residual_scale = std::sqrt(s2);

  // Standard errors.
  const std::vector<double> var = free_variances(problem, values, s2, options, out);

  std::vector<double> fitted = init;
  for (std::size_t j = 0; j < sh.free_pos.size(); ++j)
    fitted[static_cast<std::size_t>(sh.free_pos[j])] = values[j];
  out.effects = unpack(which, fitted);
  add_fitted_params(out, layout, which, init, fitted, var, options);
  if (sh.free_anchor)
    for (std::size_t i = 0; i < anchor_values.size(); i += 3)
      out.anchors.push_back({anchor_values[i], anchor_values[i + 1], anchor_values[i + 2]});

  score_fit(model, in, windows, train, held, train_before, init, fitted, mode, options, out);
  out.solve_time_s = core::seconds_since(t_start);
  return out;
}

}  // namespace odotune::diagnose
