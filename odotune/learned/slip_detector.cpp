#include <odotune/learned/slip_detector.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/enum_names.h>
#include <odotune/core/robust_stats.h>
#include <odotune/core/stopwatch.h>
#include <odotune/core/why.h>

namespace odotune::learned {
namespace {

constexpr int kSlipFeatures = SlipNet::kInputs;
static_assert(kSlipFeatures == 5, "slip features: P_r, P_l, Δct_r, Δct_l, previous variance");

bool finite_features(std::initializer_list<double> xs) {
  for (double x : xs)
    if (!std::isfinite(x)) return false;
  return true;
}

bool positive_finite_value(double x) { return x > 0.0 && std::isfinite(x); }

// The drive channels of step k (SlipFeature), NaN where the step has none.
std::array<double, 2> drive_at(const FusionInput& in, std::size_t k, SlipDrive d) {
  switch (d) {
    case SlipDrive::power: return {in.power_r[k], in.power_l[k]};
    case SlipDrive::commands: return {in.v_cmd[k], in.w_cmd[k]};
    case SlipDrive::none: return {0.0, 0.0};
  }
  return {0.0, 0.0};
}

// The odometry channels of step k.
std::array<double, 2> odometry_at(const FusionInput& in, std::size_t k) {
  if (in.input == tracks::OdometryInput::wheels) return {in.dticks_r[k], in.dticks_l[k]};
  return {in.v_kin[k], in.w_kin[k]};
}

}  // namespace

std::string_view to_string(SlipDrive d) {
  switch (d) {
    case SlipDrive::power: return "power";
    case SlipDrive::commands: return "commands";
    case SlipDrive::none: return "none";
  }
  return "power";
}

bool parse_slip_drive(std::string_view text, SlipDrive* out) {
  return core::parse_by_name(text, {SlipDrive::power, SlipDrive::commands, SlipDrive::none}, out);
}

SlipDrive available_slip_drive(const std::vector<const FusionInput*>& tracks) {
  bool power = !tracks.empty(), commands = !tracks.empty();
  for (const FusionInput* in : tracks) {
    power = power && in->has_power;
    commands = commands && in->has_cmd && in->input == tracks::OdometryInput::wheels;
  }
  return power ? SlipDrive::power : commands ? SlipDrive::commands : SlipDrive::none;
}

bool SlipDetectorModel::IsValid(std::string* why) const {
  std::string inner;
  if (!v_net.IsValid(&inner)) return core::invalid(why, "v_net: " + inner);
  if (!w_net.IsValid(&inner)) return core::invalid(why, "w_net: " + inner);
  if (!positive_finite_value(floor_var_v) || !positive_finite_value(floor_var_w))
    return core::invalid(why, fmt::format("floor_var_v = {}, floor_var_w = {}: expected finite values > 0",
                                          floor_var_v, floor_var_w));
  if (previous_lag < 1 || previous_lag > v_net.window)
    return core::invalid(why, fmt::format("previous_lag = {}: expected 1..{}", previous_lag, v_net.window));
  return true;
}

bool SlipTrainingOptions::IsValid(std::string* why) const {
  if (!training.IsValid(why)) return false;
  if (!(train_fraction > 0.0 && train_fraction < 1.0))
    return core::invalid(why, fmt::format("train_fraction = {}: expected a value in (0, 1)", train_fraction));
  if (target_window < 1 || target_window % 2 == 0)
    return core::invalid(why, fmt::format("target_window = {}: expected an odd number of steps >= 1",
                                          target_window));
  if (!positive_finite_value(floor_var_v) || !positive_finite_value(floor_var_w))
    return core::invalid(why, "floor_var_v/_w: expected finite values > 0");
  if (stride < 1) return core::invalid(why, fmt::format("stride = {}: expected >= 1", stride));
  if (!(floor_quantile >= 0.0 && floor_quantile < 1.0))
    return core::invalid(why, fmt::format("floor_quantile = {}: expected a value in [0, 1)", floor_quantile));
  if (!(weight_decay >= 0.0) || !std::isfinite(weight_decay))
    return core::invalid(why, fmt::format("weight_decay = {}: expected a finite value >= 0", weight_decay));
  if (feedback_rounds < 0)
    return core::invalid(why, fmt::format("feedback_rounds = {}: expected >= 0", feedback_rounds));
  if (!(flag_quantile > 0.0 && flag_quantile < 1.0))
    return core::invalid(why, fmt::format("flag_quantile = {}: expected a value in (0, 1)", flag_quantile));
  if (validation_chunk < 0 || patience < 1)
    return core::invalid(why, fmt::format("validation_chunk = {}, patience = {}: expected >= 0 and >= 1",
                                          validation_chunk, patience));
  if (previous_lag < 1 || previous_lag > 20)
    return core::invalid(why, fmt::format("previous_lag = {}: expected 1..20 steps", previous_lag));
  return true;
}

std::array<std::vector<double>, 2> slip_target_variances(const FusionInput& in, const OdometrySeries& odometry,
                                                         const SlipTrainingOptions& options) {
  const std::size_t n = in.size();
  std::array<std::vector<double>, 2> var;
  const std::array<const std::vector<double>*, 2> est = {&odometry.v, &odometry.w};
  const std::array<const std::vector<double>*, 2> truth = {&in.v_true, &in.w_true};
  const std::array<double, 2> floor = {options.floor_var_v, options.floor_var_w};
  const auto half = static_cast<std::size_t>(options.target_window / 2);
  for (int d = 0; d < 2; ++d) {
    std::vector<double> e2(n, std::nan(""));
    for (std::size_t k = 1; k < n; ++k)
      if (finite_features({(*est[d])[k], (*truth[d])[k]})) {
        const double e = (*est[d])[k] - (*truth[d])[k];
        e2[k] = e * e;
      }
    var[d].assign(n, std::nan(""));
    for (std::size_t k = 1; k < n; ++k) {
      double sum = 0.0;
      int m = 0;
      for (std::size_t j = k > half ? k - half : 1; j <= std::min(n - 1, k + half); ++j)
        if (std::isfinite(e2[j])) sum += e2[j], ++m;
      if (m > 0 && std::isfinite(e2[k])) var[d][k] = std::max(floor[d], sum / m);
    }
  }
  return var;
}

namespace {

using PerTrack = std::vector<std::array<std::vector<double>, 2>>;  // [track][v, w] series by step

// Checks each track and computes its variance targets (NaN where unknown).
PerTrack checked_targets(const std::vector<const FusionInput*>& tracks,
                         const std::vector<OdometrySeries>& odometry, const SlipTrainingOptions& options) {
  PerTrack targets(tracks.size());
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const FusionInput& in = *tracks[i];
    if (options.drive == SlipDrive::power && !in.has_power)
      throw std::invalid_argument(
          fmt::format("track '{}': no motor power (power_l, power_r): expected it to train the slip detector",
                      in.track_name));
    if (options.drive == SlipDrive::commands && !in.has_cmd)
      throw std::invalid_argument(fmt::format(
          "track '{}': no velocity commands (v_cmd, w_cmd): expected them to train the slip detector on",
          in.track_name));
    if (in.input != tracks.front()->input)
      throw std::invalid_argument(fmt::format(
          "track '{}' gives {} odometry, '{}' {}: expected one kind", in.track_name,
          tracks::to_string(in.input), tracks.front()->track_name, tracks::to_string(tracks.front()->input)));
    if (!in.has_gt)
      throw std::invalid_argument(
          fmt::format("track '{}': no ground truth: expected it to train the slip detector", in.track_name));
    if (odometry[i].v.size() != in.size() || odometry[i].w.size() != in.size())
      throw std::invalid_argument(fmt::format("track '{}': odometry series of {} steps for {} steps",
                                              in.track_name, odometry[i].v.size(), in.size()));
    targets[i] = slip_target_variances(in, odometry[i], options);
  }
  return targets;
}

// The floor: the configured one, raised to the `floor_quantile` of the
// odometry's own target variances (with slip a minority of the steps, the
// median is its variance while the wheels grip). A floor far below the
// odometry's real grip-time error would make the fusion filter trust it
// too much exactly where the detector sees nothing wrong.
std::array<double, 2> variance_floors(const PerTrack& targets, const SlipTrainingOptions& options) {
  std::array<double, 2> floors = {options.floor_var_v, options.floor_var_w};
  if (options.floor_quantile > 0.0) {
    for (int d = 0; d < 2; ++d) {
      std::vector<double> all;
      for (const auto& t : targets)
        for (double v : t[d])
          if (std::isfinite(v)) all.push_back(v);
      if (all.empty()) continue;
      const auto q = static_cast<std::size_t>(options.floor_quantile * static_cast<double>(all.size() - 1));
      floors[d] = std::max(floors[d], core::order_statistic(std::move(all), q));
    }
  }
  return floors;
}

// The windows of one track and dimension: every `stride`-th window whose
// inputs and target are finite; `prev` is the previous-variance series fed.
SequenceSet track_windows(const FusionInput& in, const std::vector<double>& target,
                          const std::vector<double>& prev, int window, std::size_t lag,
                          const SlipTrainingOptions& options) {
  const SlipDrive drive = options.drive;
  const auto W = static_cast<std::size_t>(window);
  std::vector<double> rows(W * kSlipFeatures);
  SequenceSet all;
  all.window = window;
  all.inputs = kSlipFeatures;
  std::size_t taken = 0;
  for (std::size_t k = W + lag; k < in.size(); ++k) {
    bool ok = std::isfinite(target[k]);
    for (std::size_t j = k + 1 - W; ok && j <= k; ++j) {
      const auto d = drive_at(in, j, drive), o = odometry_at(in, j);
      ok = finite_features({d[0], d[1], o[0], o[1], prev[j - lag]});
    }
    if (!ok) continue;
    if (taken++ % static_cast<std::size_t>(options.stride) != 0) continue;
    for (std::size_t r = 0; r < W; ++r) {
      const std::size_t j = k + 1 - W + r;
      const auto d = drive_at(in, j, drive), o = odometry_at(in, j);
      double* row = &rows[r * kSlipFeatures];
      row[kSlipPowerR] = d[0];
      row[kSlipPowerL] = d[1];
      row[kSlipDticksR] = o[0];
      row[kSlipDticksL] = o[1];
      row[kSlipPrevious] = prev[j - lag];
    }
    all.add(rows.data(), target[k]);
  }
  return all;
}

// The windows of every track, split 70/30 per track; `previous[i][d]` is
// the previous-variance series fed (log-ratio, by step).
void build_windows(const std::vector<const FusionInput*>& tracks, const PerTrack& targets,
                   const PerTrack& previous, int window, std::size_t lag, const SlipTrainingOptions& options,
                   std::array<SequenceSet, 2>* train, std::array<SequenceSet, 2>* val) {
  for (int d = 0; d < 2; ++d) {
    (*train)[d] = (*val)[d] = SequenceSet{};
    (*train)[d].window = (*val)[d].window = window;
    (*train)[d].inputs = (*val)[d].inputs = kSlipFeatures;
  }
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const FusionInput& in = *tracks[i];
    for (int d = 0; d < 2; ++d) {
      const SequenceSet all = track_windows(in, targets[i][d], previous[i][d], window, lag, options);
      if (all.size() < 10)
        throw std::invalid_argument(
            fmt::format("track '{}': only {} usable windows for the slip detector: expected at least 10",
                        in.track_name, all.size()));
      auto [t, v] = split_sequences(all, options.train_fraction);
      (*train)[d].append(t);
      (*val)[d].append(v);
    }
  }
}

// One fit of `net` (fresh: train_lstm, else retrain_lstm from its weights),
// in validation chunks when asked (see SlipTrainingOptions::validation_chunk).
LstmTrainingSummary fit_slip_net(SlipNet& net, const SequenceSet& t, const SequenceSet& v,
                                 LstmTrainingOptions opts, bool fresh, std::vector<double>* curve,
                                 const SlipTrainingOptions& options) {
  curve->clear();
  if (options.validation_chunk <= 0 || v.size() == 0) {
    LstmTrainingSummary r = fresh ? train_lstm(net, t, v, opts) : retrain_lstm(net, t, opts);
    if (v.size() > 0) r.validation_mae = lstm_mae(net, v);
    return r;
  }
  const int total = opts.max_iterations;
  // The first chunk runs the loss continuation (lstm_training.h), one chunk
  // per stage; later chunks stay at the final MAE scale.
  int stages = 1;
  for (double a = opts.mae_scale_start; a > opts.mae_scale; a /= 10.0) ++stages;
  opts.max_iterations = std::min(total, stages * options.validation_chunk);
  LstmTrainingSummary r = fresh ? train_lstm(net, t, v, opts) : retrain_lstm(net, t, opts);
  int used = r.iterations;
  double best = lstm_mae(net, v);
  curve->push_back(best);
  SlipNet best_net = net;
  LstmTrainingSummary best_r = r;
  best_r.validation_mae = best;
  opts.mae_scale_start = opts.mae_scale;
  int stale = 0;
  while (used < total && stale < options.patience) {
    opts.max_iterations = std::min(options.validation_chunk, total - used);
    r = retrain_lstm(net, t, opts);
    used += std::max(1, r.iterations);
    const double mae = lstm_mae(net, v);
    curve->push_back(mae);
    if (r.usable && mae < best) {
      best = mae, best_net = net, best_r = r, best_r.validation_mae = mae, stale = 0;
    } else {
      ++stale;
    }
    if (r.iterations < opts.max_iterations) break;  // converged
  }
  net = best_net;
  best_r.iterations = used;
  return best_r;
}

// The previous-variance input was held at 0 in the first fit, so its
// kernel row never got a gradient: zero it and give it the targets'
// scale, so the refits start from the first fit's function exactly.
void reset_previous_input(SlipDetectorModel& model, const std::array<SequenceSet, 2>& train) {
  for (auto [net, set] : {std::pair{&model.v_net, &train[0]}, std::pair{&model.w_net, &train[1]}}) {
    using L = LstmLayout<kSlipFeatures, SlipNet::kHidden>;
    constexpr std::size_t first = L::kKernel + kSlipPrevious * L::kGates;
    for (std::size_t n = 0; n < L::kGates; ++n) net->weights[first + n] = 0.0;
    double sum = 0.0, sum2 = 0.0;
    for (double y : set->y) sum += y, sum2 += y * y;
    const double m = sum / static_cast<double>(set->size());
    net->input_mean[kSlipPrevious] = m;
    net->input_sd[kSlipPrevious] = std::max(
        1e-3, std::sqrt(std::max(0.0, sum2 / static_cast<double>(set->size()) - m * m)));
  }
}

// The detector's own outputs on every training track, as log-ratios.
PerTrack own_log_ratios(const std::vector<const FusionInput*>& tracks, const SlipDetectorModel& model,
                        const std::array<double, 2>& floors) {
  PerTrack own(tracks.size());
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const FusionInput& in = *tracks[i];
    SlipDetectorStepper stepper(&model);
    for (int d = 0; d < 2; ++d) own[i][d].assign(in.size(), 0.0);
    for (std::size_t k = 1; k < in.size(); ++k) {
      const auto var = stepper.step(in, k);
      own[i][0][k] = std::log(var[0] / floors[0]);
      own[i][1][k] = std::log(var[1] / floors[1]);
    }
  }
  return own;
}

// The flag thresholds: the quantile of the detector's own variances over the
// training tracks (SlipDetectorModel::flag_var_v).
void set_flag_thresholds(const std::vector<const FusionInput*>& tracks, double quantile,
                         SlipDetectorModel& model) {
  std::array<std::vector<double>, 2> all;
  for (const FusionInput* in : tracks) {
    SlipDetectorStepper stepper(&model);
    for (std::size_t k = 1; k < in->size(); ++k) {
      const auto var = stepper.step(*in, k);
      if (static_cast<int>(k) > model.v_net.window) all[0].push_back(var[0]), all[1].push_back(var[1]);
    }
  }
  for (int d = 0; d < 2; ++d) {
    if (all[d].empty()) continue;
    const auto q = static_cast<std::size_t>(quantile * static_cast<double>(all[d].size() - 1));
    (d == 0 ? model.flag_var_v : model.flag_var_w) = core::order_statistic(std::move(all[d]), q);
  }
}

}  // namespace

SlipDetectorModel train_slip_detector(const std::vector<const FusionInput*>& tracks,
                                      const std::vector<OdometrySeries>& odometry,
                                      const SlipTrainingOptions& options, SlipTrainingSummary* summary) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("slip detector training: " + why);
  if (tracks.empty() || tracks.size() != odometry.size())
    throw std::invalid_argument(
        fmt::format("slip detector training: {} tracks and {} odometry series: expected the same number, >= 1",
                    tracks.size(), odometry.size()));
  SlipDetectorModel model;
  // Trained with a linear output; the stepper applies the ReLU (see the
  // header: training through the ReLU leaves the windows whose output starts
  // below zero without a gradient, and most slip windows start there).
  model.v_net.activation = model.w_net.activation = OutputActivation::linear;
  model.previous_lag = options.previous_lag;
  model.drive = options.drive;
  model.input = tracks.front()->input;
  const auto lag = static_cast<std::size_t>(options.previous_lag);
  const int window = model.v_net.window;

  PerTrack targets = checked_targets(tracks, odometry, options);
  const std::array<double, 2> floors = variance_floors(targets, options);
  model.floor_var_v = floors[0];
  model.floor_var_w = floors[1];
  for (auto& t : targets)
    for (int d = 0; d < 2; ++d)
      for (double& v : t[d]) v = std::log(std::max(v, floors[d]) / floors[d]);  // NaN stays NaN
  std::array<SequenceSet, 2> train, val;
  if (options.teacher_forcing) {
    build_windows(tracks, targets, targets, window, lag, options, &train, &val);
  } else {
    PerTrack held(tracks.size());
    for (std::size_t i = 0; i < tracks.size(); ++i)
      for (int d = 0; d < 2; ++d) held[i][d].assign(tracks[i]->size(), 0.0);
    build_windows(tracks, targets, held, window, lag, options, &train, &val);
  }
  double max_v = 0.0, max_w = 0.0;
  for (double y : train[0].y) max_v = std::max(max_v, y);
  for (double y : train[1].y) max_w = std::max(max_w, y);
  model.max_log_ratio_v = max_v;
  model.max_log_ratio_w = max_w;
  const auto start = std::chrono::steady_clock::now();
  SlipTrainingSummary s;
  LstmTrainingOptions v_opts = options.training;
  v_opts.weight_decay = options.weight_decay;
  s.v = fit_slip_net(model.v_net, train[0], val[0], v_opts, true, &s.v_curve, options);
  LstmTrainingOptions w_opts = v_opts;
  w_opts.seed = options.training.seed + 1000;
  s.w = fit_slip_net(model.w_net, train[1], val[1], w_opts, true, &s.w_curve, options);
  if (!options.teacher_forcing) reset_previous_input(model, train);
  for (int round = 0; round < options.feedback_rounds; ++round) {
    const PerTrack own = own_log_ratios(tracks, model, floors);
    build_windows(tracks, targets, own, window, lag, options, &train, &val);
    s.v = fit_slip_net(model.v_net, train[0], val[0], v_opts, false, &s.v_curve, options);
    s.w = fit_slip_net(model.w_net, train[1], val[1], w_opts, false, &s.w_curve, options);
  }
  set_flag_thresholds(tracks, options.flag_quantile, model);
  s.seconds = core::seconds_since(start);
  s.train_windows = train[0].size();
  s.validation_windows = val[0].size();
  if (!model.IsValid(&why))
    throw std::invalid_argument("slip detector training produced an unusable model: " + why);
  if (summary) *summary = s;
  return model;
}

SlipDetectorStepper::SlipDetectorStepper(const SlipDetectorModel* model)
    : model_(model),
      v_rows_(static_cast<std::size_t>(model->v_net.window) * kSlipFeatures, 0.0),
      w_rows_(static_cast<std::size_t>(model->w_net.window) * kSlipFeatures, 0.0),
      previous_{model->floor_var_v, model->floor_var_w},
      history_(static_cast<std::size_t>(model->previous_lag), std::array<double, 2>{0.0, 0.0}) {}

std::array<double, 2> SlipDetectorStepper::step(const FusionInput& in, std::size_t k) {
  // A missing drive sample (NaN) would poison 20 windows: hold the last one.
  const auto d = drive_at(in, k, model_->drive);
  if (std::isfinite(d[0])) last_drive_[0] = d[0];
  if (std::isfinite(d[1])) last_drive_[1] = d[1];
  const auto o = odometry_at(in, k);
  auto push = [&](std::vector<double>& rows, double previous) {
    std::copy(rows.begin() + kSlipFeatures, rows.end(), rows.begin());
    double* last = &rows[rows.size() - kSlipFeatures];
    last[kSlipPowerR] = last_drive_[0];
    last[kSlipPowerL] = last_drive_[1];
    last[kSlipDticksR] = o[0];
    last[kSlipDticksL] = o[1];
    last[kSlipPrevious] = previous;
  };
  // The log-ratio the detector gave previous_lag steps ago (0 = the floor).
  const std::array<double, 2> fed = history_.front();
  push(v_rows_, fed[0]);
  push(w_rows_, fed[1]);
  if (filled_ < model_->v_net.window) ++filled_;
  std::array<double, 2> y = history_.back();
  if (filled_ >= model_->v_net.window) {
    // Non-finite increments give a non-finite output: keep the last one.
    const double v = model_->v_net.predict(v_rows_.data());
    const double w = model_->w_net.predict(w_rows_.data());
    if (std::isfinite(v)) y[0] = std::clamp(v, 0.0, model_->max_log_ratio_v);
    if (std::isfinite(w)) y[1] = std::clamp(w, 0.0, model_->max_log_ratio_w);
  }
  std::rotate(history_.begin(), history_.begin() + 1, history_.end());
  history_.back() = y;
  previous_ = {model_->floor_var_v * std::exp(y[0]), model_->floor_var_w * std::exp(y[1])};
  return previous_;
}

}  // namespace odotune::learned
