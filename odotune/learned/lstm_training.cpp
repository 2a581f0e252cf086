// LSTM training with Ceres (odotune/learned/lstm_training.h). All Jet-heavy code
// (AutoDiffCostFunction over LstmResidual) is instantiated in this one TU.
#include <odotune/learned/lstm_training.h>

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <memory>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/counter_rng.h>
#include <odotune/core/why.h>

namespace odotune::learned {

namespace {

// Stream id of the initial-weight draws in counter_uniform01 (any constant
// distinct from other users of the seed).
constexpr std::uint64_t kInitStream = 0x6c73746dULL;  // "lstm"

void require(bool ok, const std::string& why) {
  if (!ok) throw std::invalid_argument(why);
}

// Evaluates every window's residual (and Jacobian row) for the current
// weights in one OpenMP loop before Ceres asks the residual blocks, which then
// only copy their slot (CachedCost). Ceres updates the user's parameter block
// before calling PrepareForEvaluation when a callback is set (Solver docs,
// EvaluationCallback). Each window writes its own slot and nothing is summed
// across threads, so results do not depend on num_threads.
template <int K>
class WindowCache final : public ceres::EvaluationCallback {
 public:
  WindowCache(const double* params, std::vector<std::unique_ptr<ceres::CostFunction>> inner, int num_threads)
      : params_(params),
        inner_(std::move(inner)),
        num_threads_(num_threads),
        point_(K, 0.0),
        residuals_(inner_.size(), 0.0),
        jacobians_(inner_.size() * static_cast<std::size_t>(K), 0.0),
        ok_(inner_.size(), 0) {}

  void PrepareForEvaluation(bool evaluate_jacobians, bool new_evaluation_point) override {
    if (!new_evaluation_point && have_point_ && (have_jacobians_ || !evaluate_jacobians)) return;
    std::copy(params_, params_ + K, point_.begin());
    const long n = static_cast<long>(inner_.size());
#pragma omp parallel for num_threads(num_threads_) schedule(static)
    for (long w = 0; w < n; ++w) {
      const double* p = point_.data();
      double* row = jacobians_.data() + static_cast<std::size_t>(w) * K;
      double* jac[1] = {row};
      ok_[static_cast<std::size_t>(w)] = inner_[static_cast<std::size_t>(w)]->Evaluate(
                                             &p, &residuals_[static_cast<std::size_t>(w)],
                                             evaluate_jacobians ? jac : nullptr)
                                             ? 1
                                             : 0;
    }
    have_point_ = true;
    have_jacobians_ = evaluate_jacobians;
  }

  // Whether the cache holds the point `parameters`, bit for bit (an equal value
  // with other bits, -0.0 for 0.0, only costs a re-evaluation).
  bool holds(const double* parameters) const {
    if (!have_point_) return false;
    // clang-format off
    return std::memcmp(parameters, point_.data(), sizeof(double) * K) == 0;  // NOLINT(bugprone-suspicious-memory-comparison): the bits are the key
    // clang-format on
  }

  // All residuals at `parameters` (non-finite where an evaluation failed).
  const std::vector<double>& residuals_at(const double* parameters) {
    if (!holds(parameters)) {
      const double* saved = params_;
      params_ = parameters;
      PrepareForEvaluation(false, true);
      params_ = saved;
    }
    for (std::size_t w = 0; w < ok_.size(); ++w)
      if (!ok_[w]) residuals_[w] = std::numeric_limits<double>::quiet_NaN();
    return residuals_;
  }

  // Window w's residual (and Jacobian row) at `parameters`: from the cache
  // when it holds that point, else evaluated directly.
  bool Evaluate(std::size_t w, const double* parameters, double* residual, double* row) const {
    const bool cached = (row == nullptr || have_jacobians_) && holds(parameters);
    if (!cached) {
      double* jac[1] = {row};
      return inner_[w]->Evaluate(&parameters, residual, row != nullptr ? jac : nullptr);
    }
    if (!ok_[w]) return false;
    *residual = residuals_[w];
    if (row != nullptr) std::copy_n(jacobians_.data() + w * K, K, row);
    return true;
  }

 private:
  const double* params_;
  std::vector<std::unique_ptr<ceres::CostFunction>> inner_;
  int num_threads_;
  std::vector<double> point_, residuals_, jacobians_;
  std::vector<char> ok_;
  bool have_point_ = false, have_jacobians_ = false;
};

template <int K>
class CachedCost final : public ceres::SizedCostFunction<1, K> {
 public:
  CachedCost(const WindowCache<K>* cache, std::size_t w) : cache_(cache), w_(w) {}
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    return cache_->Evaluate(w_, parameters[0], residuals, jacobians != nullptr ? jacobians[0] : nullptr);
  }

 private:
  const WindowCache<K>* cache_;
  std::size_t w_;
};

// ½·λ·‖w − w̄‖² as the residual block √λ·(w − w̄) (Jacobian √λ·I).
template <int K>
class WeightDecay final : public ceres::SizedCostFunction<K, K> {
 public:
  WeightDecay(double lambda, const std::array<double, K>& centre)
      : sqrt_lambda_(std::sqrt(lambda)), centre_(centre) {}
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    for (int n = 0; n < K; ++n)
      residuals[n] = sqrt_lambda_ * (parameters[0][n] - centre_[static_cast<std::size_t>(n)]);
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      std::fill_n(jacobians[0], K * K, 0.0);
      for (int n = 0; n < K; ++n) jacobians[0][n * K + n] = sqrt_lambda_;
    }
    return true;
  }

 private:
  double sqrt_lambda_;
  std::array<double, K> centre_;
};

// Population mean and sd (paper eq. 4); a zero or non-finite sd becomes 1.
std::pair<double, double> mean_sd(const std::vector<double>& v, std::size_t first, std::size_t stride) {
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = first; i < v.size(); i += stride, ++n) sum += v[i];
  const double mean = sum / static_cast<double>(n);
  double ss = 0.0;
  for (std::size_t i = first; i < v.size(); i += stride) ss += (v[i] - mean) * (v[i] - mean);
  double sd = std::sqrt(ss / static_cast<double>(n));
  if (!(sd > 0.0) || !std::isfinite(sd)) sd = 1.0;
  return {mean, sd};
}

void check_options(const LstmTrainingOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("LSTM training options: " + why);
}

void check_set(const SequenceSet& set, int inputs, const char* name) {
  std::string why;
  if (!set.IsValid(&why)) throw std::invalid_argument(std::string(name) + " set: " + why);
  require(set.inputs == inputs, std::string(name) + " set: inputs = " + std::to_string(set.inputs) +
                                    ", expected " + std::to_string(inputs) + " (the net's input count)");
}

// ½ Σ ρ(r_n²) at options.mae_scale (+ ½·λ·‖w‖²): the objective the summary
// reports, the same at both ends whatever the continuation stages were.
// Residuals come from the cache's evaluators (parallel, summed in order).
template <int K>
double robust_cost(WindowCache<K>& cache, const double* params, std::size_t n,
                   const LstmTrainingOptions& options, const std::array<double, K>& centre) {
  const std::vector<double>& r = cache.residuals_at(params);
  const ceres::SoftLOneLoss loss(options.mae_scale);
  double cost = 0.0;
  for (std::size_t w = 0; w < n; ++w) {
    double rho[3];
    loss.Evaluate(r[w] * r[w], rho);
    cost += 0.5 * rho[0];
  }
  if (options.weight_decay > 0.0)
    for (int k = 0; k < K; ++k) {
      const double d = params[k] - centre[static_cast<std::size_t>(k)];
      cost += 0.5 * options.weight_decay * d * d;
    }
  return cost;
}

// `train`'s windows standardised with net's standardisation (window after
// window in *z) and their standardised targets.
template <int I, int H>
void standardise_windows(const LstmNet<I, H>& net, const SequenceSet& train, std::vector<double>* z,
                         std::vector<double>* target) {
  const std::size_t n = train.size();
  const std::size_t per_window = static_cast<std::size_t>(net.window) * I;
  z->resize(n * per_window);
  target->resize(n);
  for (std::size_t w = 0; w < n; ++w) {
    net.standardise(train.window_data(w), z->data() + w * per_window);
    (*target)[w] = (train.y[w] - net.output_mean) / net.output_sd;
  }
}

// One residual per window (BPTT or automatic derivatives), reading its
// inputs from z, which must outlive them.
template <int I, int H>
std::vector<std::unique_ptr<ceres::CostFunction>> window_costs(const LstmNet<I, H>& net,
                                                               const std::vector<double>& z,
                                                               const std::vector<double>& target,
                                                               const LstmTrainingOptions& options) {
  constexpr int K = LstmLayout<I, H>::kCount;
  const std::size_t n = target.size();
  const std::size_t per_window = static_cast<std::size_t>(net.window) * I;
  std::vector<std::unique_ptr<ceres::CostFunction>> inner;
  inner.reserve(n);
  for (std::size_t w = 0; w < n; ++w) {
    const double* xw = z.data() + w * per_window;
    if (options.jacobian == LstmTrainingOptions::Jacobian::bptt) {
      inner.push_back(std::make_unique<LstmBpttCost<I, H>>(xw, net.window, target[w], net.activation));
    } else {
      inner.push_back(std::make_unique<ceres::AutoDiffCostFunction<LstmResidual<I, H>, 1, K>>(
          new LstmResidual<I, H>{xw, net.window, target[w], net.activation}));
    }
  }
  return inner;
}

ceres::Solver::Options solver_options_for(const LstmTrainingOptions& options) {
  ceres::Solver::Options solver_options;
  solver_options.minimizer_type = ceres::TRUST_REGION;
  solver_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  // Normal equations: the Jacobian is tall (windows × K) and dense; JᵀJ
  // (K × K) is cheaper to factor than QR of J and LM's damping keeps it
  // positive definite.
  solver_options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  solver_options.function_tolerance = options.function_tolerance;
  solver_options.num_threads = 1;  // see the header: parallelism is in WindowCache
  solver_options.minimizer_progress_to_stdout = false;
  solver_options.logging_type = ceres::SILENT;
  return solver_options;
}

// Early stopping (LstmTrainingOptions::early_stopping_patience): the
// validation MAE of the weights Ceres holds after each iteration
// (update_state_every_iteration), the best weights kept. Each window's error
// lands in its own slot and the slots are summed in order, so the curve does
// not depend on the thread count.
template <int I, int H>
class EarlyStopping final : public ceres::IterationCallback {
 public:
  static constexpr int K = LstmLayout<I, H>::kCount;
  EarlyStopping(const LstmNet<I, H>& net, const SequenceSet& validation, const std::array<double, K>* params,
                int patience, int num_threads)
      : net_(net), y_(validation.y), params_(params), patience_(patience), num_threads_(num_threads) {
    std::vector<double> target;
    standardise_windows(net, validation, &z_, &target);
    errors_.resize(y_.size());
    record(0);
  }
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    // Iteration 0 of a later continuation stage repeats the last point.
    if (summary.iteration == 0) return ceres::SOLVER_CONTINUE;
    ++iterations_;
    record(iterations_);
    return stopped() ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }
  // Patience counts from the last continuation stage on: the earlier ones
  // (a coarse loss) can sit on a plateau before the fit moves.
  void arm() {
    armed_ = true;
    since_best_ = 0;
  }
  bool stopped() const { return armed_ && since_best_ >= patience_; }
  const std::array<double, K>& best() const { return best_; }
  int best_iteration() const { return best_iteration_; }
  const std::vector<double>& curve() const { return curve_; }

 private:
  void record(int iteration) {
    const long n = static_cast<long>(y_.size());
    const std::size_t per = static_cast<std::size_t>(net_.window) * I;
    const double* w = params_->data();
#pragma omp parallel for num_threads(num_threads_) schedule(static)
    for (long i = 0; i < n; ++i) {
      const auto u = static_cast<std::size_t>(i);
      const double out = net_.output_mean + net_.output_sd * lstm_forward<I, H, double>(w, z_.data() + u * per,
                                                                                        net_.window,
                                                                                        net_.activation);
      errors_[u] = std::abs(out - y_[u]);
    }
    double sum = 0.0;
    for (double e : errors_) sum += e;
    const double mae = n > 0 ? sum / static_cast<double>(n) : 0.0;
    curve_.push_back(mae);
    if (curve_.size() == 1 || mae < best_mae_) {
      best_mae_ = mae;
      best_ = *params_;
      best_iteration_ = iteration;
      since_best_ = 0;
    } else {
      ++since_best_;
    }
  }
  const LstmNet<I, H>& net_;
  std::vector<double> z_, errors_;
  const std::vector<double>& y_;
  const std::array<double, K>* params_;
  int patience_, num_threads_;
  std::array<double, K> best_{};
  double best_mae_ = 0.0;
  int best_iteration_ = 0, since_best_ = 0, iterations_ = 0;
  bool armed_ = false;
  std::vector<double> curve_;
};

// Continuation scales: mae_scale_start, ÷10 per stage, ending at mae_scale.
std::vector<double> continuation_scales(const LstmTrainingOptions& options) {
  std::vector<double> scales;
  for (double a = options.mae_scale_start; a > options.mae_scale; a /= 10.0) scales.push_back(a);
  scales.push_back(options.mae_scale);
  return scales;
}

// The Ceres solve shared by train_lstm and retrain_lstm: standardises `train`
// with net's standardisation and minimises from net.weights. Writes the
// weights into `net` only when usable.
template <int I, int H>
LstmTrainingSummary solve(LstmNet<I, H>& net, const SequenceSet& train, const LstmTrainingOptions& options,
                          const SequenceSet* early_stopping = nullptr) {
  constexpr int K = LstmLayout<I, H>::kCount;
  const std::size_t n = train.size();
  std::vector<double> z, target;
  standardise_windows(net, train, &z, &target);

  std::array<double, K> params = net.weights;
  std::array<double, K> centre{};  // the decay's centre w̄
  if (options.decay_to_start) centre = net.weights;
  WindowCache<K> cache(params.data(), window_costs(net, z, target, options), options.num_threads);
  // The loss is swapped between the continuation stages (ceres::LossFunctionWrapper
  // is Ceres' documented way to anneal a loss scale).
  ceres::LossFunctionWrapper loss(new ceres::SoftLOneLoss(options.mae_scale), ceres::TAKE_OWNERSHIP);
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.evaluation_callback = &cache;
  ceres::Problem problem(problem_options);
  for (std::size_t w = 0; w < n; ++w)
    problem.AddResidualBlock(new CachedCost<K>(&cache, w), &loss, params.data());
  if (options.weight_decay > 0.0)
    problem.AddResidualBlock(new WeightDecay<K>(options.weight_decay, centre), nullptr, params.data());

  ceres::Solver::Options solver_options = solver_options_for(options);
  const std::vector<double> scales = continuation_scales(options);
  std::optional<EarlyStopping<I, H>> stopping;
  if (early_stopping != nullptr) {
    stopping.emplace(net, *early_stopping, &params, options.early_stopping_patience, options.num_threads);
    solver_options.update_state_every_iteration = true;
    solver_options.callbacks.push_back(&*stopping);
  }

  LstmTrainingSummary summary;
  summary.initial_cost = robust_cost<K>(cache, params.data(), n, options, centre);
  ceres::Solver::Summary ceres_summary;
  bool failed = false;
  int budget = options.max_iterations;
  int taken = 0;  // iterations run, iteration 0 of each solve (its start) not counted
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t stage = 0; stage < scales.size(); ++stage) {
    const int stages_left = static_cast<int>(scales.size() - stage);
    solver_options.max_num_iterations = stage + 1 == scales.size() ? budget : budget / stages_left;
    if (options.stop_after_iterations > 0) {
      const int left = options.stop_after_iterations - taken;
      if (left <= 0) break;
      solver_options.max_num_iterations = std::min(solver_options.max_num_iterations, left);
    }
    loss.Reset(new ceres::SoftLOneLoss(scales[stage]), ceres::TAKE_OWNERSHIP);
    if (stopping && stage + 1 == scales.size()) stopping->arm();
    ceres::Solve(solver_options, &problem, &ceres_summary);
    const int used = ceres_summary.num_successful_steps + ceres_summary.num_unsuccessful_steps;
    taken += std::max(0, static_cast<int>(ceres_summary.iterations.size()) - 1);
    summary.iterations += used;
    budget = std::max(0, budget - used);
    if (ceres_summary.termination_type == ceres::FAILURE) {
      failed = true;
      break;
    }
    if (stopping && stopping->stopped()) break;
  }
  if (stopping && !failed) {
    params = stopping->best();
    summary.best_iteration = stopping->best_iteration();
    summary.validation_curve = stopping->curve();
  }
  const auto stop = std::chrono::steady_clock::now();

  summary.termination = std::string(ceres::TerminationTypeToString(ceres_summary.termination_type)) + ": " +
                        ceres_summary.message;
  summary.final_cost = robust_cost<K>(cache, params.data(), n, options, centre);
  summary.seconds = std::chrono::duration<double>(stop - start).count();
  const bool finite = std::all_of(params.begin(), params.end(), [](double v) { return std::isfinite(v); });
  summary.usable = finite && !failed && std::isfinite(summary.final_cost);
  if (summary.usable) net.weights = params;
  return summary;
}

}  // namespace

bool SequenceSet::IsValid(std::string* why) const {
  if (window < 1) return core::invalid(why, "window = " + std::to_string(window) + ": expected ≥ 1");
  if (inputs < 1) return core::invalid(why, "inputs = " + std::to_string(inputs) + ": expected ≥ 1");
  const std::size_t per = static_cast<std::size_t>(window) * static_cast<std::size_t>(inputs);
  if (x.size() != y.size() * per)
    return core::invalid(why,
                         "x has " + std::to_string(x.size()) +
                             " values, expected size() × window × inputs = " + std::to_string(y.size() * per));
  for (std::size_t n = 0; n < y.size(); ++n) {
    if (!std::isfinite(y[n])) return core::invalid(why, "y[" + std::to_string(n) + "] is not finite");
    for (std::size_t i = 0; i < per; ++i)
      if (!std::isfinite(x[n * per + i]))
        return core::invalid(why, "window " + std::to_string(n) + " has a non-finite x value");
  }
  return true;
}

std::pair<SequenceSet, SequenceSet> split_sequences(const SequenceSet& all, double fraction) {
  require(fraction >= 0.0 && fraction <= 1.0,
          "split_sequences: fraction = " + fmt::format("{}", fraction) + ", expected a value in [0, 1]");
  std::string why;
  if (!all.IsValid(&why)) throw std::invalid_argument("split_sequences: " + why);
  const std::size_t n = all.size();
  const auto n_first = static_cast<std::size_t>(std::llround(fraction * static_cast<double>(n)));
  const std::size_t per = static_cast<std::size_t>(all.window) * static_cast<std::size_t>(all.inputs);
  std::pair<SequenceSet, SequenceSet> out;
  for (SequenceSet* s : {&out.first, &out.second}) {
    s->window = all.window;
    s->inputs = all.inputs;
  }
  const auto split_x = all.x.begin() + static_cast<std::ptrdiff_t>(n_first * per);
  const auto split_y = all.y.begin() + static_cast<std::ptrdiff_t>(n_first);
  out.first.x.assign(all.x.begin(), split_x);
  out.first.y.assign(all.y.begin(), split_y);
  out.second.x.assign(split_x, all.x.end());
  out.second.y.assign(split_y, all.y.end());
  return out;
}

bool LstmTrainingOptions::IsValid(std::string* why) const {
  if (max_iterations < 0)
    return core::invalid(why, "max_iterations = " + std::to_string(max_iterations) + ": expected ≥ 0");
  if (!(mae_scale > 0.0) || !std::isfinite(mae_scale))
    return core::invalid(why, "mae_scale = " + fmt::format("{}", mae_scale) + ": expected a finite value > 0");
  if (!(mae_scale_start > 0.0) || !std::isfinite(mae_scale_start))
    return core::invalid(why, "mae_scale_start = " + fmt::format("{}", mae_scale_start) +
                                  ": expected a finite value > 0");
  if (!(function_tolerance >= 0.0) || !std::isfinite(function_tolerance))
    return core::invalid(why, "function_tolerance = " + fmt::format("{}", function_tolerance) +
                                  ": expected a finite value ≥ 0");
  if (!(weight_decay >= 0.0) || !std::isfinite(weight_decay))
    return core::invalid(why,
                         "weight_decay = " + fmt::format("{}", weight_decay) + ": expected a finite value ≥ 0");
  if (num_threads < 1)
    return core::invalid(why, "num_threads = " + std::to_string(num_threads) + ": expected ≥ 1");
  if (early_stopping_patience < 0)
    return core::invalid(why, "early_stopping_patience = " + std::to_string(early_stopping_patience) +
                                  ": expected ≥ 0");
  if (stop_after_iterations < 0)
    return core::invalid(why,
                         "stop_after_iterations = " + std::to_string(stop_after_iterations) + ": expected ≥ 0");
  return true;
}

template <int I, int H>
std::array<double, LstmLayout<I, H>::kCount> lstm_initial_weights(std::uint64_t seed) {
  using L = LstmLayout<I, H>;
  std::array<double, L::kCount> w{};
  auto uniform = [seed](int n, double limit) {
    return limit *
           (2.0 * core::counter_uniform01(seed, 0, static_cast<std::uint64_t>(n), 0, kInitStream) - 1.0);
  };
  const double kernel = std::sqrt(6.0 / (I + L::kGates));
  const double recurrent = std::sqrt(6.0 / (H + L::kGates));
  const double dense = std::sqrt(6.0 / (H + 1));
  for (int n = L::kKernel; n < L::kRecurrent; ++n) w[n] = uniform(n, kernel);
  for (int n = L::kRecurrent; n < L::kBias; ++n) w[n] = uniform(n, recurrent);
  for (int j = 0; j < H; ++j) w[L::kBias + H + j] = 1.0;  // forget gate
  for (int n = L::kDense; n < L::kDenseBias; ++n) w[n] = uniform(n, dense);
  return w;
}

template <int I, int H>
double lstm_mae(const LstmNet<I, H>& net, const SequenceSet& set) {
  std::string why;
  if (!net.IsValid(&why)) throw std::invalid_argument("lstm_mae: net: " + why);
  require(set.inputs == I && set.window == net.window,
          "lstm_mae: set has window " + std::to_string(set.window) + " × inputs " + std::to_string(set.inputs) +
              ", expected the net's " + std::to_string(net.window) + " × " + std::to_string(I));
  require(set.x.size() == set.size() * static_cast<std::size_t>(set.window) * I,
          "lstm_mae: set x has " + std::to_string(set.x.size()) + " values, expected size() × window × inputs");
  if (set.size() == 0) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0.0;
  for (std::size_t n = 0; n < set.size(); ++n) sum += std::abs(net.predict(set.window_data(n)) - set.y[n]);
  return sum / static_cast<double>(set.size());
}

template <int I, int H>
LstmTrainingSummary train_lstm(LstmNet<I, H>& net, const SequenceSet& train, const SequenceSet& validation,
                               const LstmTrainingOptions& options) {
  check_options(options);
  check_set(train, I, "train");
  require(train.size() > 0, "train set: empty, expected at least one window");
  require(train.window <= LstmNet<I, H>::kMaxWindow, "train set: window = " + std::to_string(train.window) +
                                                         ", expected ≤ " +
                                                         std::to_string(LstmNet<I, H>::kMaxWindow));
  if (validation.size() > 0) {  // an empty validation set of any shape means "none"
    check_set(validation, I, "validation");
    require(validation.window == train.window, "validation set: window = " + std::to_string(validation.window) +
                                                   ", expected the train set's " +
                                                   std::to_string(train.window));
  }

  LstmNet<I, H> candidate = net;
  candidate.window = train.window;
  for (int k = 0; k < I; ++k) {
    const auto [mean, sd] = mean_sd(train.x, static_cast<std::size_t>(k), static_cast<std::size_t>(I));
    candidate.input_mean[k] = mean;
    candidate.input_sd[k] = sd;
  }
  const auto [y_mean, y_sd] = mean_sd(train.y, 0, 1);
  candidate.output_mean = y_mean;
  candidate.output_sd = y_sd;
  if (candidate.activation == OutputActivation::relu)
    candidate.output_mean = *std::min_element(train.y.begin(), train.y.end());
  candidate.weights = lstm_initial_weights<I, H>(options.seed);
  if (options.zero_output_start) {
    candidate.output_mean = 0.0;
    for (int j = 0; j <= H; ++j) candidate.weights[LstmLayout<I, H>::kDense + j] = 0.0;
  }

  const bool stop_early = options.early_stopping_patience > 0 && validation.size() > 0;
  LstmTrainingSummary summary = solve(candidate, train, options, stop_early ? &validation : nullptr);
  if (!summary.usable) return summary;
  summary.train_mae = lstm_mae(candidate, train);
  if (validation.size() > 0) summary.validation_mae = lstm_mae(candidate, validation);
  net = candidate;
  return summary;
}

template <int I, int H>
LstmTrainingSummary retrain_lstm(LstmNet<I, H>& net, const SequenceSet& train,
                                 const LstmTrainingOptions& options) {
  check_options(options);
  std::string why;
  if (!net.IsValid(&why)) throw std::invalid_argument("retrain_lstm: net: " + why);
  check_set(train, I, "train");
  require(train.size() > 0, "train set: empty, expected at least one window");
  require(train.window == net.window, "train set: window = " + std::to_string(train.window) +
                                          ", expected the net's " + std::to_string(net.window));
  LstmNet<I, H> candidate = net;
  LstmTrainingSummary summary = solve(candidate, train, options);
  if (!summary.usable) return summary;
  summary.train_mae = lstm_mae(candidate, train);
  net = candidate;
  return summary;
}

#define ODOTUNE_INSTANTIATE_LSTM_TRAINING(I, H)                                                         \
  template std::array<double, LstmLayout<I, H>::kCount> lstm_initial_weights<I, H>(std::uint64_t);      \
  template double lstm_mae<I, H>(const LstmNet<I, H>&, const SequenceSet&);                             \
  template LstmTrainingSummary train_lstm<I, H>(LstmNet<I, H>&, const SequenceSet&, const SequenceSet&, \
                                                const LstmTrainingOptions&);                            \
  template LstmTrainingSummary retrain_lstm<I, H>(LstmNet<I, H>&, const SequenceSet&,                   \
                                                  const LstmTrainingOptions&);

ODOTUNE_INSTANTIATE_LSTM_TRAINING(3, 3)
ODOTUNE_INSTANTIATE_LSTM_TRAINING(3, 5)
ODOTUNE_INSTANTIATE_LSTM_TRAINING(3, 8)
ODOTUNE_INSTANTIATE_LSTM_TRAINING(5, 10)

#undef ODOTUNE_INSTANTIATE_LSTM_TRAINING

}  // namespace odotune::learned
