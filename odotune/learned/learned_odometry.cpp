#include <odotune/learned/learned_odometry.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/counter_rng.h>
#include <odotune/core/enum_names.h>
#include <odotune/core/stopwatch.h>
#include <odotune/core/why.h>

namespace odotune::learned {
namespace {

constexpr int kFeatures = OdometryNet::kInputs;
static_assert(kFeatures == 3, "learned odometry features: three per step");

// Uniform noise of standard deviation sd (±sd·√3), from the counter RNG so a
// seeded training set is the same whatever the thread count.
double teacher_noise(double sd, std::uint64_t seed, std::size_t track, std::size_t step, int which) {
  if (sd <= 0.0) return 0.0;
  const double u = core::counter_uniform01(seed, track, step, static_cast<std::uint64_t>(which), 0x7ea);
  return sd * std::sqrt(3.0) * (2.0 * u - 1.0);
}

bool finite_all(std::initializer_list<double> xs) {
  for (double x : xs)
    if (!std::isfinite(x)) return false;
  return true;
}

bool finite_row(const double* row) { return finite_all({row[0], row[1], row[2]}); }

}  // namespace

std::string_view to_string(LearnedTarget t) {
  return t == LearnedTarget::correction ? "correction" : "velocity";
}

bool parse_learned_target(std::string_view text, LearnedTarget* out) {
  return core::parse_by_name(text, {LearnedTarget::velocity, LearnedTarget::correction}, out);
}

std::string_view to_string(LearnedValidation v) {
  switch (v) {
    case LearnedValidation::chronological: return "chronological";
    case LearnedValidation::recordings: return "recordings";
    case LearnedValidation::blocks: return "blocks";
  }
  return "chronological";
}

bool parse_learned_validation(std::string_view text, LearnedValidation* out) {
  return core::parse_by_name(
      text, {LearnedValidation::chronological, LearnedValidation::recordings, LearnedValidation::blocks}, out);
}

std::string_view to_string(LearnedFeatures f) {
  switch (f) {
    case LearnedFeatures::paper: return "paper";
    case LearnedFeatures::channel: return "channel";
    case LearnedFeatures::both: return "both";
  }
  return "paper";
}

bool parse_learned_features(std::string_view text, LearnedFeatures* out) {
  return core::parse_by_name(text, {LearnedFeatures::paper, LearnedFeatures::channel, LearnedFeatures::both},
                             out);
}

bool LearnedOdometryModel::IsValid(std::string* why) const {
  std::string inner;
  if (!v_net.IsValid(&inner)) return core::invalid(why, "v_net: " + inner);
  if (!w_net.IsValid(&inner)) return core::invalid(why, "w_net: " + inner);
  if (v_net.units() != w_net.units() || v_net.window() != w_net.window())
    return core::invalid(why, fmt::format("v_net has {} units × {} steps, w_net {} × {}: expected one shape",
                                          v_net.units(), v_net.window(), w_net.units(), w_net.window()));
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz))
    return core::invalid(why, fmt::format("rate_hz = {}: expected a finite value > 0", rate_hz));
  const bool wheels = input == tracks::OdometryInput::wheels;
  if (wheels && (!(ticks_per_rev > 0.0) || !std::isfinite(ticks_per_rev)))
    return core::invalid(why, fmt::format("ticks_per_rev = {}: expected a finite value > 0", ticks_per_rev));
  const bool paper = features == LearnedFeatures::paper;
  if (paper != (target == LearnedTarget::velocity))
    return core::invalid(why,
                         fmt::format("features '{}' with target '{}': the paper's features are the velocity "
                                     "nets', correction nets read channel or both",
                                     to_string(features), to_string(target)));
  if (paper && (!wheels || gyro))
    return core::invalid(why,
                         "the paper's velocity nets read wheel increments only (no twist, commands or gyro)");
  if (!(v_validation_mae >= 0.0) || !(w_validation_mae >= 0.0) || !(v_kinematic_mae >= 0.0) ||
      !(w_kinematic_mae >= 0.0) ||
      !std::isfinite(v_validation_mae + w_validation_mae + v_kinematic_mae + w_kinematic_mae))
    return core::invalid(why, "validation MAEs must be finite values >= 0");
  return true;
}

bool LearnedTrainingOptions::IsValid(std::string* why) const {
  if (!training.IsValid(why)) return false;
  if (!(train_fraction > 0.0 && train_fraction < 1.0))
    return core::invalid(why, fmt::format("train_fraction = {}: expected a value in (0, 1)", train_fraction));
  if (!(previous_noise_v >= 0.0) || !(previous_noise_w >= 0.0) || !std::isfinite(previous_noise_v) ||
      !std::isfinite(previous_noise_w))
    return core::invalid(why, "previous_noise_v/_w: expected finite values >= 0");
  if (restarts < 1 || restarts > 100)
    return core::invalid(why, fmt::format("restarts = {}: expected 1..100", restarts));
  if (validation == LearnedValidation::blocks)
    return core::invalid(why, "validation on blocks is the correction nets' (odometry_selection.h)");
  return true;
}

void feature_row(const FusionInput& in, std::size_t k, LearnedFeatures features, double gyro_z, int which,
                 double previous, double* row) {
  switch (features) {
    case LearnedFeatures::paper:
      row[kFeatDticksR] = in.dticks_r[k];
      row[kFeatDticksL] = in.dticks_l[k];
      row[kFeatPrevious] = previous;
      return;
    case LearnedFeatures::channel:
      row[0] = which == 0 ? in.v_kin[k] : in.w_kin[k];
      row[1] = which == 0 ? 0.0 : gyro_z;
      row[2] = 0.0;
      return;
    case LearnedFeatures::both:
      row[0] = in.v_kin[k];
      row[1] = in.w_kin[k];
      row[2] = gyro_z;
      return;
  }
}

void append_velocity_windows(const FusionInput& in, const WindowSpec& spec, std::size_t first, std::size_t end,
                             SequenceSet* v_set, SequenceSet* w_set) {
  const bool correction = spec.target == LearnedTarget::correction;
  const bool paper = spec.features == LearnedFeatures::paper;
  end = std::min(end, in.size());
  const auto W = static_cast<std::size_t>(spec.window);
  std::vector<double> v_rows(W * kFeatures), w_rows(W * kFeatures);
  // Step j's features need the increments over step j (step 0 has none)
  // and, for the paper's layout, the truth of step j − 1: the window
  // (k − W, k] needs steps from max(first, 1) on, and from max(first, 1) − 1
  // for the previous velocity.
  const std::size_t k0 = std::max<std::size_t>(first, 1) + (paper ? W : W - 1);
  for (std::size_t k = k0; k < end; ++k) {
    bool ok = finite_all({in.v_true[k], in.w_true[k]}) &&
              (!correction || finite_all({in.v_kin[k], in.w_kin[k]}));
    for (std::size_t r = 0; ok && r < W; ++r) {
      const std::size_t j = k + 1 - W + r;
      const double g = spec.gyro ? in.gyro_z[j] : 0.0;
      const double pv = paper ? in.v_true[j - 1] + teacher_noise(spec.previous_noise_v, spec.seed, 0, j, 0)
                              : 0.0;
      const double pw = paper ? in.w_true[j - 1] + teacher_noise(spec.previous_noise_w, spec.seed, 0, j, 1)
                              : 0.0;
      feature_row(in, j, spec.features, g, 0, pv, &v_rows[r * kFeatures]);
      feature_row(in, j, spec.features, g, 1, pw, &w_rows[r * kFeatures]);
      ok = finite_row(&v_rows[r * kFeatures]) && finite_row(&w_rows[r * kFeatures]);
    }
    if (!ok) continue;
    v_set->add(v_rows.data(), in.v_true[k] - (correction ? in.v_kin[k] : 0.0));
    w_set->add(w_rows.data(), in.w_true[k] - (correction ? in.w_kin[k] : 0.0));
  }
}

bool model_fits(const LearnedOdometryModel& model, const FusionInput& in, std::string* why) {
  if (in.input != model.input)
    return core::invalid(why,
                         fmt::format("track '{}' gives {} odometry, the model was trained on {}", in.track_name,
                                     tracks::to_string(in.input), tracks::to_string(model.input)));
  if (model.input == tracks::OdometryInput::wheels &&
      std::abs(in.ticks_per_rev - model.ticks_per_rev) > 1e-9 * model.ticks_per_rev)
    return core::invalid(
        why, fmt::format("track '{}' has ticks_per_rev = {}, the model was trained with {}; expected "
                         "the same robot",
                         in.track_name, in.ticks_per_rev, model.ticks_per_rev));
  if (model.gyro && !in.has_gyro)
    return core::invalid(why,
                         fmt::format("track '{}' has no gyro (gyro_z); the model reads one", in.track_name));
  if (std::abs(1.0 / in.dt_s - model.rate_hz) > 1e-9 * model.rate_hz)
    return core::invalid(why, fmt::format("track '{}' is laid out at {} Hz, the model runs at {} Hz",
                                          in.track_name, 1.0 / in.dt_s, model.rate_hz));
  return true;
}

namespace {

// The first validation step of track i of n (size() when it has none).
std::size_t first_validation_step(std::size_t i, std::size_t n, std::size_t steps,
                                  const LearnedTrainingOptions& options) {
  if (options.validation == LearnedValidation::chronological)
    return static_cast<std::size_t>(options.train_fraction * static_cast<double>(steps));
  const auto held = std::max<std::size_t>(
      1, static_cast<std::size_t>(std::llround(static_cast<double>(n) * (1.0 - options.train_fraction))));
  return i + held >= n ? 0 : steps;
}

// The training and validation windows of the V and W nets.
struct WindowSets {
  SequenceSet v_train, v_val, w_train, w_val;
};

void check_paper_track(const FusionInput& in, const LearnedOdometryModel& model, double dt_s) {
  if (!in.has_gt)
    throw std::invalid_argument(
        fmt::format("track '{}': no ground truth (gt_x, gt_y, gt_theta): expected it to learn odometry from",
                    in.track_name));
  if (in.input != tracks::OdometryInput::wheels)
    throw std::invalid_argument(fmt::format("track '{}': {} odometry; the paper's velocity nets read wheel "
                                            "increments (train correction nets for this input)",
                                            in.track_name, tracks::to_string(in.input)));
  if (std::abs(in.ticks_per_rev - model.ticks_per_rev) > 1e-9 * model.ticks_per_rev)
    throw std::invalid_argument(
        fmt::format("track '{}': ticks_per_rev = {} differs from the first track's {}: expected one robot",
                    in.track_name, in.ticks_per_rev, model.ticks_per_rev));
  if (std::abs(in.dt_s - dt_s) > 1e-12)
    throw std::invalid_argument(fmt::format("track '{}': fusion step {} s differs from the first track's {} s",
                                            in.track_name, in.dt_s, dt_s));
}

// Checks each track against the first (one robot, one step) and splits its
// windows into training and validation.
WindowSets training_windows(const std::vector<const FusionInput*>& tracks, const LearnedOdometryModel& model,
                            int window, const LearnedTrainingOptions& options) {
  WindowSets ws;
  for (SequenceSet* s : {&ws.v_train, &ws.v_val, &ws.w_train, &ws.w_val}) {
    s->window = window;
    s->inputs = kFeatures;
  }
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const FusionInput& in = *tracks[i];
    check_paper_track(in, model, tracks.front()->dt_s);
    SequenceSet v_all, w_all;
    v_all.window = w_all.window = window;
    v_all.inputs = w_all.inputs = kFeatures;
    WindowSpec spec;
    spec.window = window;
    spec.previous_noise_v = options.previous_noise_v;
    spec.previous_noise_w = options.previous_noise_w;
    spec.seed = options.training.seed + i;
    append_velocity_windows(in, spec, &v_all, &w_all);
    if (v_all.size() < 10)
      throw std::invalid_argument(
          fmt::format("track '{}': only {} windows of {} steps with ground truth: expected at least 10",
                      in.track_name, v_all.size(), window));
    const double keep = options.validation == LearnedValidation::chronological ? options.train_fraction
                        : first_validation_step(i, tracks.size(), in.size(), options) == 0 ? 0.0
                                                                                           : 1.0;
    auto [vt, vv] = split_sequences(v_all, keep);
    auto [wt, wv] = split_sequences(w_all, keep);
    ws.v_train.append(vt);
    ws.v_val.append(vv);
    ws.w_train.append(wt);
    ws.w_val.append(wv);
  }
  return ws;
}

// MAE of V and W over the validation steps (first_validation_step) of the
// series `series_of(track)` gives.
template <class SeriesOf>
std::array<double, 2> validation_mae(const std::vector<const FusionInput*>& tracks,
                                     const LearnedTrainingOptions& options, SeriesOf series_of) {
  std::array<double, 2> sum{0.0, 0.0};
  std::size_t count = 0;
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const FusionInput* in = tracks[i];
    const std::size_t first = first_validation_step(i, tracks.size(), in->size(), options);
    if (first >= in->size()) continue;
    const OdometrySeries run = series_of(*in);
    for (std::size_t k = std::max<std::size_t>(first, 1); k < in->size(); ++k)
      if (finite_all({run.v[k], run.w[k], in->v_true[k], in->w_true[k]})) {
        sum[0] += std::abs(run.v[k] - in->v_true[k]);
        sum[1] += std::abs(run.w[k] - in->w_true[k]);
        ++count;
      }
  }
  const double inf = std::numeric_limits<double>::infinity();
  return count > 0
             ? std::array<double, 2>{sum[0] / static_cast<double>(count), sum[1] / static_cast<double>(count)}
             : std::array<double, 2>{inf, inf};
}

// A restart's score, free-running: each net fed its own previous output, as
// when it runs alone (run_learned_odometry). A net can have a small one-step
// (teacher-forced) validation MAE and still drift on its own outputs. The V
// and W nets do not feed each other, so a pair is scored in one run.
std::array<double, 2> free_running_mae(const std::vector<const FusionInput*>& tracks,
                                       const LearnedOdometryModel& m, const LearnedTrainingOptions& options) {
  return validation_mae(tracks, options, [&m](const FusionInput& in) { return run_learned_odometry(in, m); });
}

}  // namespace

LearnedOdometryModel train_learned_odometry(const std::vector<const FusionInput*>& tracks,
                                            const LearnedTrainingOptions& options,
                                            LearnedTrainingSummary* summary) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("learned odometry training: " + why);
  if (tracks.empty()) throw std::invalid_argument("learned odometry training: no tracks given");
  if (options.validation == LearnedValidation::recordings && tracks.size() < 2)
    throw std::invalid_argument(
        "learned odometry training: validation on recordings needs at least 2 tracks (one to hold out)");
  LearnedOdometryModel model;
  const int window = model.v_net.window();
  model.rate_hz = 1.0 / tracks.front()->dt_s;
  model.ticks_per_rev = tracks.front()->ticks_per_rev;
  const WindowSets ws = training_windows(tracks, model, window, options);

  const auto start = std::chrono::steady_clock::now();
  LearnedTrainingSummary s;
  // Best of options.restarts starts (see LearnedTrainingOptions::restarts),
  // scored free-running (free_running_mae).
  const LearnedOdometryModel fresh = model;
  std::array<double, 2> best_mae{0.0, 0.0};
  for (int r = 0; r < options.restarts; ++r) {
    LearnedOdometryModel candidate = fresh;
    LstmTrainingOptions o = options.training;
    o.seed = options.training.seed + 7919u * static_cast<std::uint64_t>(r);
    const LstmTrainingSummary tv = candidate.v_net.train(ws.v_train, ws.v_val, o);
    o.seed += 1000;  // a different initialisation for the W net
    const LstmTrainingSummary tw = candidate.w_net.train(ws.w_train, ws.w_val, o);
    std::array<double, 2> mae = free_running_mae(tracks, candidate, options);
    if (!tv.usable) mae[0] = std::numeric_limits<double>::infinity();
    if (!tw.usable) mae[1] = std::numeric_limits<double>::infinity();
    s.v_restart_mae.push_back(mae[0]);
    s.w_restart_mae.push_back(mae[1]);
    if (r == 0 || (tv.usable && (!s.v.usable || mae[0] < best_mae[0])))
      s.v = tv, best_mae[0] = mae[0], s.v_restart = r, model.v_net = candidate.v_net;
    if (r == 0 || (tw.usable && (!s.w.usable || mae[1] < best_mae[1])))
      s.w = tw, best_mae[1] = mae[1], s.w_restart = r, model.w_net = candidate.w_net;
  }
  const std::array<double, 2> kin = validation_mae(tracks, options, [](const FusionInput& in) {
    return kinematic_odometry(in);
  });
  s.v_kinematic_mae = kin[0];
  s.w_kinematic_mae = kin[1];
  s.seconds = core::seconds_since(start);
  s.train_windows = ws.v_train.size();
  s.validation_windows = ws.v_val.size();
  model.v_validation_mae = std::isfinite(s.v.validation_mae) ? s.v.validation_mae : s.v.train_mae;
  model.w_validation_mae = std::isfinite(s.w.validation_mae) ? s.w.validation_mae : s.w.train_mae;
  model.v_kinematic_mae = std::isfinite(kin[0]) ? kin[0] : 0.0;
  model.w_kinematic_mae = std::isfinite(kin[1]) ? kin[1] : 0.0;
  if (!model.IsValid(&why))
    throw std::invalid_argument("learned odometry training produced an unusable model: " + why);
  if (summary) *summary = s;
  return model;
}

LearnedOdometryStepper::LearnedOdometryStepper(const LearnedOdometryModel* model)
    : model_(model),
      v_rows_(static_cast<std::size_t>(model->v_net.window()) * kFeatures, 0.0),
      w_rows_(static_cast<std::size_t>(model->w_net.window()) * kFeatures, 0.0) {}

std::array<double, 2> LearnedOdometryStepper::step(const FusionInput& in, std::size_t k, double previous_v,
                                                   double previous_w) {
  const LearnedOdometryModel& m = *model_;
  if (m.gyro && std::isfinite(in.gyro_z[k])) last_gyro_ = in.gyro_z[k];
  const double g = m.gyro ? last_gyro_ : 0.0;
  auto push = [&](std::vector<double>& rows, int which, double previous) {
    // Shift the window one row (20 × 3 doubles: cheaper than a ring's
    // index arithmetic in predict, which wants the rows contiguous).
    std::copy(rows.begin() + kFeatures, rows.end(), rows.begin());
    feature_row(in, k, m.features, g, which, previous, &rows[rows.size() - kFeatures]);
  };
  push(v_rows_, 0, previous_v);
  push(w_rows_, 1, previous_w);
  const int window = m.v_net.window();
  if (filled_ < window) ++filled_;
  if (filled_ < window) return {in.v_kin[k], in.w_kin[k]};
  const double v = m.v_net.predict(v_rows_.data()), w = m.w_net.predict(w_rows_.data());
  if (m.target == LearnedTarget::correction) return {in.v_kin[k] + v, in.w_kin[k] + w};
  return {v, w};
}

OdometrySeries run_learned_odometry(const FusionInput& in, const LearnedOdometryModel& model, std::size_t first,
                                    std::size_t end) {
  OdometrySeries s;
  s.v.assign(in.size(), 0.0);
  s.w.assign(in.size(), 0.0);
  end = std::min(end, in.size());
  LearnedOdometryStepper stepper(&model);
  double pv = 0.0, pw = 0.0;
  for (std::size_t k = std::max<std::size_t>(first + 1, 1); k < end; ++k) {
    const auto vw = stepper.step(in, k, pv, pw);
    s.v[k] = pv = vw[0];
    s.w[k] = pw = vw[1];
  }
  return s;
}

OdometrySeries kinematic_odometry(const FusionInput& in) { return {in.v_kin, in.w_kin}; }

}  // namespace odotune::learned
