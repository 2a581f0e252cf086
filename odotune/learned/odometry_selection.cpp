#include <odotune/learned/odometry_selection.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/robust_stats.h>
#include <odotune/core/stopwatch.h>
#include <odotune/core/why.h>
#include <odotune/learned/odometry_metrics.h>

namespace odotune::learned {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Position measures of a fold: dead reckoning restarted every 10 s and
// every 60 s, and over the whole unit (0).
constexpr std::array<double, 3> kPoseWindowsS = {10.0, 60.0, 0.0};
// Fewest windows a fit trains on.
constexpr std::size_t kMinWindows = 50;

struct Unit {
  StepSpan span;
  std::string name;
};

[[noreturn]] void fail_selection(const std::string& what) {
  throw std::invalid_argument("correction nets: " + what);
}

void check_tracks(const std::vector<const FusionInput*>& tracks) {
  if (tracks.empty()) fail_selection("no tracks given");
  const FusionInput& a = *tracks.front();
  for (const FusionInput* in : tracks) {
    if (!in->has_gt)
      fail_selection(
          fmt::format("track '{}': no ground truth (gt_x, gt_y, gt_theta): expected it to learn odometry from",
                      in->track_name));
    if (in->input != a.input)
      fail_selection(fmt::format("track '{}' gives {} odometry, track '{}' {}: expected one kind",
                                 in->track_name, tracks::to_string(in->input), a.track_name,
                                 tracks::to_string(a.input)));
    if (std::abs(in->dt_s - a.dt_s) > 1e-12)
      fail_selection(fmt::format("track '{}': step {} s differs from the first track's {} s", in->track_name,
                                 in->dt_s, a.dt_s));
    if (a.input == tracks::OdometryInput::wheels &&
        std::abs(in->ticks_per_rev - a.ticks_per_rev) > 1e-9 * a.ticks_per_rev)
      fail_selection(
          fmt::format("track '{}': ticks_per_rev = {} differs from the first track's {}: expected one robot",
                      in->track_name, in->ticks_per_rev, a.ticks_per_rev));
  }
}

// Whole recordings, or blocks of block_s (a last piece shorter than half a
// block joins the block before it).
std::vector<Unit> make_units(const std::vector<const FusionInput*>& tracks, const SelectionOptions& o) {
  std::vector<Unit> units;
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const FusionInput& in = *tracks[i];
    if (o.validation == LearnedValidation::recordings) {
      units.push_back({{i, 0, in.size()}, in.track_name});
      continue;
    }
    const auto block = static_cast<std::size_t>(std::llround(o.block_s / in.dt_s));
    std::size_t first = 0;
    while (first < in.size()) {
      std::size_t end = std::min(in.size(), first + block);
      if (in.size() - end < block / 2) end = in.size();
      units.push_back({{i, first, end},
                       fmt::format("{} {:.0f}-{:.0f} s", in.track_name, in.t[first] - in.t[0],
                                   in.t[end - 1] - in.t[0] + in.dt_s)});
      first = end;
    }
  }
  return units;
}

std::vector<CorrectionSettings> candidates(const SelectionOptions& o) {
  std::vector<CorrectionSettings> out;
  for (int u : o.units)
    for (int w : o.windows)
      for (double d : o.weight_decays)
        for (LearnedFeatures f : o.features) out.push_back({u, w, d, f});
  return out;
}

LearnedOdometryModel fresh_model(const CorrectionSettings& s, const FusionInput& first, bool gyro) {
  LearnedOdometryModel m;
  m.v_net = OdometryNet::with_units(s.units, s.window);
  m.w_net = OdometryNet::with_units(s.units, s.window);
  m.rate_hz = 1.0 / first.dt_s;
  m.ticks_per_rev = first.input == tracks::OdometryInput::wheels ? first.ticks_per_rev : 0.0;
  m.target = LearnedTarget::correction;
  m.input = first.input;
  m.features = s.features;
  m.gyro = gyro;
  return m;
}

// The V and W windows of the given units.
std::array<SequenceSet, 2> windows_of(const std::vector<const FusionInput*>& tracks,
                                      const std::vector<Unit>& units, const std::vector<std::size_t>& which,
                                      const CorrectionSettings& s, bool gyro) {
  std::array<SequenceSet, 2> out;
  for (SequenceSet& set : out) {
    set.window = s.window;
    set.inputs = OdometryNet::kInputs;
  }
  WindowSpec spec;
  spec.window = s.window;
  spec.features = s.features;
  spec.gyro = gyro;
  spec.target = LearnedTarget::correction;
  for (std::size_t u : which) {
    const StepSpan& sp = units[u].span;
    append_velocity_windows(*tracks[sp.track], spec, sp.first, sp.end, &out[0], &out[1]);
  }
  return out;
}

LstmTrainingOptions fit_options(const SelectionOptions& o, const CorrectionSettings& s) {
  LstmTrainingOptions t = o.training;
  t.zero_output_start = true;
  t.weight_decay = s.weight_decay;
  t.decay_to_start = false;
  return t;
}

// The stopped nets' measures on the fold's units.
FoldMeasures measure(const std::vector<const FusionInput*>& tracks, const std::vector<Unit>& units,
                     const std::vector<std::size_t>& fold, const LearnedOdometryModel& model) {
  FoldMeasures fm;
  std::array<double, 2> v_sum{}, w_sum{};
  std::size_t count = 0;
  std::array<std::array<PoseErrorSum, 3>, kNetCombinations> pose{};
  for (std::size_t u : fold) {
    const StepSpan& sp = units[u].span;
    const FusionInput& in = *tracks[sp.track];
    fm.units.push_back(units[u].name);
    const OdometrySeries nets = run_learned_odometry(in, model, sp.first, sp.end);
    for (std::size_t k = sp.first + 1; k < sp.end; ++k) {
      if (!std::isfinite(in.v_true[k]) || !std::isfinite(in.w_true[k])) continue;
      v_sum[0] += std::abs(in.v_kin[k] - in.v_true[k]);
      v_sum[1] += std::abs(nets.v[k] - in.v_true[k]);
      w_sum[0] += std::abs(in.w_kin[k] - in.w_true[k]);
      w_sum[1] += std::abs(nets.w[k] - in.w_true[k]);
      ++count;
    }
    for (int c = 0; c < kNetCombinations; ++c) {
      const std::vector<double>& v = (c & 1) ? nets.v : in.v_kin;
      const std::vector<double>& w = (c & 2) ? nets.w : in.w_kin;
      for (std::size_t m = 0; m < kPoseWindowsS.size(); ++m)
        pose[static_cast<std::size_t>(c)][m].add(dead_reckoning_errors(in, v, w, kPoseWindowsS[m], sp.first,
                                                                       sp.end));
    }
  }
  const double n = static_cast<double>(count);
  fm.v_mae = {count ? v_sum[0] / n : kNaN, count ? v_sum[1] / n : kNaN};
  fm.w_mae = {count ? w_sum[0] / n : kNaN, count ? w_sum[1] / n : kNaN};
  for (std::size_t c = 0; c < pose.size(); ++c)
    for (std::size_t m = 0; m < kPoseWindowsS.size(); ++m) fm.pose_rmse[c][m] = pose[c][m].rmse();
  return fm;
}

}  // namespace

void score_candidate(CandidateResult& r) {
  const auto folds = static_cast<double>(r.folds.size());
  for (int c = 0; c < kNetCombinations; ++c) {
    const auto ci = static_cast<std::size_t>(c);
    const bool uses_v = (c & 1) != 0, uses_w = (c & 2) != 0;
    bool every_fold = true;
    std::vector<double>& fs = r.fold_scores[ci];
    fs.clear();
    for (const FoldMeasures& f : r.folds) {
      const auto& p = f.pose_rmse[ci];
      const auto& k = f.pose_rmse[0];
      double mean_log = 0.0;
      for (std::size_t m = 0; m < p.size(); ++m)
        mean_log += std::log(p[m] / k[m]) / static_cast<double>(p.size());
      fs.push_back(std::isfinite(mean_log) ? mean_log : std::numeric_limits<double>::infinity());
      const bool v_ok = !uses_v || f.v_mae[1] < f.v_mae[0];
      const bool w_ok = !uses_w || f.w_mae[1] < f.w_mae[0];
      every_fold = every_fold && v_ok && w_ok && p[2] <= k[2];
    }
    double mean = 0.0, ss = 0.0;
    for (double x : fs) mean += x / folds;
    for (double x : fs) ss += (x - mean) * (x - mean);
    r.score[ci] = c == 0 ? 0.0 : mean;
    r.score_se[ci] = c == 0 || fs.size() < 2 ? 0.0 : std::sqrt(ss / (folds - 1.0)) / std::sqrt(folds);
    r.qualifies[ci] = c == 0 || (every_fold && mean < 0.0);
  }
}

namespace {

// Simpler first (the header's order): channel before both, fewer units, a
// shorter window, a larger decay.
bool simpler(const CorrectionSettings& a, const CorrectionSettings& b) {
  const int fa = a.features == LearnedFeatures::channel ? 0 : 1,
            fb = b.features == LearnedFeatures::channel ? 0 : 1;
  if (fa != fb) return fa < fb;
  if (a.units != b.units) return a.units < b.units;
  if (a.window != b.window) return a.window < b.window;
  return a.weight_decay > b.weight_decay;
}

}  // namespace

void choose_candidate(SelectionSummary& s) {
  double best = std::numeric_limits<double>::infinity(), best_se = 0.0, best_any = best;
  std::size_t any = 0;
  for (std::size_t i = 0; i < s.candidates.size(); ++i)
    for (std::size_t c = 1; c < kNetCombinations; ++c) {
      const CandidateResult& r = s.candidates[i];
      if (r.score[c] < best_any) best_any = r.score[c], any = i;
      if (r.qualifies[c] && r.score[c] < best) best = r.score[c], best_se = r.score_se[c];
    }
  s.chosen = any;
  s.combination = NetCombination::kinematic;
  if (!std::isfinite(best)) return;
  bool found = false;
  for (std::size_t i = 0; i < s.candidates.size(); ++i) {
    const CandidateResult& r = s.candidates[i];
    std::size_t pick = 0;
    for (std::size_t c = 1; c < kNetCombinations; ++c)
      if (r.qualifies[c] && r.score[c] <= best + best_se && (pick == 0 || r.score[c] < r.score[pick])) pick = c;
    if (pick == 0 || (found && !simpler(r.settings, s.candidates[s.chosen].settings))) continue;
    found = true;
    s.chosen = i;
    s.combination = static_cast<NetCombination>(pick);
  }
}

namespace {

// One candidate over every fold.
CandidateResult cross_validate(const std::vector<const FusionInput*>& tracks, const std::vector<Unit>& units,
                               const std::vector<std::vector<std::size_t>>& folds, const CorrectionSettings& s,
                               bool gyro, const SelectionOptions& o, const std::function<void()>& fitted) {
  CandidateResult r;
  r.settings = s;
  const LstmTrainingOptions t = fit_options(o, s);
  for (const std::vector<std::size_t>& fold : folds) {
    std::vector<std::size_t> rest;
    for (std::size_t u = 0; u < units.size(); ++u)
      if (std::find(fold.begin(), fold.end(), u) == fold.end()) rest.push_back(u);
    const auto train = windows_of(tracks, units, rest, s, gyro);
    const auto held = windows_of(tracks, units, fold, s, gyro);
    if (train[0].size() < kMinWindows || held[0].size() < 1)
      fail_selection(
          fmt::format("a fold holding {} trains on {} windows and is judged on {}: expected at least {} and 1 "
                      "(longer recordings, or --validation blocks with shorter blocks)",
                      units[fold.front()].name, train[0].size(), held[0].size(), kMinWindows));
    LearnedOdometryModel m = fresh_model(s, *tracks.front(), gyro);
    LstmTrainingOptions tv = t, tw = t;
    tw.seed += 1000;  // a different initialisation for the W net
    const LstmTrainingSummary sv = m.v_net.train(train[0], held[0], tv);
    const LstmTrainingSummary sw = m.w_net.train(train[1], held[1], tw);
    if (!sv.usable) m.v_net.zero_output();
    if (!sw.usable) m.w_net.zero_output();
    FoldMeasures fm = measure(tracks, units, fold, m);
    fm.v_iteration = sv.usable ? sv.best_iteration : 0;
    fm.w_iteration = sw.usable ? sw.best_iteration : 0;
    r.folds.push_back(std::move(fm));
    if (fitted) fitted();
  }
  score_candidate(r);
  return r;
}

int median_iterations(const std::vector<FoldMeasures>& folds, bool v) {
  std::vector<double> its;
  its.reserve(folds.size());
  for (const FoldMeasures& f : folds) its.push_back(v ? f.v_iteration : f.w_iteration);
  return std::max(1, static_cast<int>(std::lround(core::median(its))));
}

}  // namespace

std::string CorrectionSettings::label() const {
  return fmt::format("{} units, {} steps, decay {:g}, {}", units, window, weight_decay, to_string(features));
}

std::string_view to_string(NetCombination c) {
  switch (c) {
    case NetCombination::kinematic: return "kinematic";
    case NetCombination::v_net: return "V net";
    case NetCombination::w_net: return "W net";
    case NetCombination::both: return "V and W nets";
  }
  return "kinematic";
}

bool SelectionOptions::IsValid(std::string* why) const {
  if (!training.IsValid(why)) return false;
  if (training.early_stopping_patience < 1)
    return core::invalid(why, fmt::format("early_stopping_patience = {}: expected >= 1",
                                          training.early_stopping_patience));
  if (validation != LearnedValidation::recordings && validation != LearnedValidation::blocks)
    return core::invalid(why,
                         fmt::format("validation '{}': expected recordings or blocks", to_string(validation)));
  if (max_folds < 2) return core::invalid(why, fmt::format("max_folds = {}: expected >= 2", max_folds));
  if (units.empty() || windows.empty() || weight_decays.empty() || features.empty())
    return core::invalid(why, "every list of candidate settings needs at least one value");
  for (int u : units)
    if (std::find(kOdometryNetUnits.begin(), kOdometryNetUnits.end(), u) == kOdometryNetUnits.end())
      return core::invalid(why, fmt::format("units {}: expected one of 3, 5, 8", u));
  for (int w : windows)
    if (w < 2 || w > 256) return core::invalid(why, fmt::format("window {}: expected 2..256 steps", w));
  for (double d : weight_decays)
    if (!(d >= 0.0) || !std::isfinite(d))
      return core::invalid(why, fmt::format("weight decay {}: expected >= 0", d));
  for (LearnedFeatures f : features)
    if (f == LearnedFeatures::paper)
      return core::invalid(why, "features 'paper': correction nets read channel or both");
  if (validation == LearnedValidation::blocks && !(block_s > 0.0 && std::isfinite(block_s)))
    return core::invalid(why, fmt::format("block_s = {}: expected a finite length > 0 s", block_s));
  return true;
}

LearnedOdometryModel train_correction_odometry(const std::vector<const FusionInput*>& tracks,
                                               const SelectionOptions& options, SelectionSummary* summary,
                                               const SelectionProgress& progress) {
  std::string why;
  if (!options.IsValid(&why)) fail_selection(why);
  check_tracks(tracks);
  const auto start = std::chrono::steady_clock::now();
  const std::vector<Unit> units = make_units(tracks, options);
  if (units.size() < 2)
    fail_selection(fmt::format("{} unit to validate on: expected at least 2 ({})", units.size(),
                               options.validation == LearnedValidation::recordings
                                   ? "give two recordings or more, or --validation blocks"
                                   : "a recording longer than two blocks, or shorter blocks"));
  const std::size_t n_folds = std::min<std::size_t>(units.size(), static_cast<std::size_t>(options.max_folds));
  std::vector<std::vector<std::size_t>> folds(n_folds);
  for (std::size_t u = 0; u < units.size(); ++u) folds[u % n_folds].push_back(u);
  bool gyro = options.use_gyro;
  for (const FusionInput* in : tracks) gyro = gyro && in->has_gyro;

  SelectionSummary s;
  for (const Unit& u : units) s.units.push_back(u.name);
  s.folds = static_cast<int>(n_folds);
  s.gyro = gyro;
  const std::vector<CorrectionSettings> grid = candidates(options);
  const long total = static_cast<long>(grid.size() * n_folds) + 1;
  long done = 0;
  if (progress) progress(done, total);
  const auto fitted = [&] {
    if (progress) progress(++done, total);
  };
  for (const CorrectionSettings& c : grid)
    s.candidates.push_back(cross_validate(tracks, units, folds, c, gyro, options, fitted));
  choose_candidate(s);

  // The chosen setting on every unit, each net for its folds' median stop.
  const CandidateResult& c = s.candidates[s.chosen];
  LearnedOdometryModel model = fresh_model(c.settings, *tracks.front(), gyro);
  std::vector<std::size_t> all(units.size());
  for (std::size_t u = 0; u < all.size(); ++u) all[u] = u;
  const auto train = windows_of(tracks, units, all, c.settings, gyro);
  LstmTrainingOptions t = fit_options(options, c.settings);
  t.early_stopping_patience = 0;
  s.v_iterations = median_iterations(c.folds, true);
  s.w_iterations = median_iterations(c.folds, false);
  LstmTrainingOptions tv = t, tw = t;
  tv.stop_after_iterations = s.v_iterations;
  tw.stop_after_iterations = s.w_iterations;
  tw.seed += 1000;
  s.v = model.v_net.train(train[0], {}, tv);
  s.w = model.w_net.train(train[1], {}, tw);
  const bool keep_v = s.v.usable &&
                      (s.combination == NetCombination::v_net || s.combination == NetCombination::both);
  const bool keep_w = s.w.usable &&
                      (s.combination == NetCombination::w_net || s.combination == NetCombination::both);
  if (!keep_v) model.v_net.zero_output();
  if (!keep_w) model.w_net.zero_output();
  model.v_beats_kinematic = keep_v;
  model.w_beats_kinematic = keep_w;
  // The folds' pooled MAE of the kept nets (the kinematics' where zeroed).
  double v_sum = 0.0, w_sum = 0.0, vk_sum = 0.0, wk_sum = 0.0;
  for (const FoldMeasures& f : c.folds) {
    v_sum += f.v_mae[keep_v ? 1 : 0], w_sum += f.w_mae[keep_w ? 1 : 0];
    vk_sum += f.v_mae[0], wk_sum += f.w_mae[0];
  }
  const auto folds_n = static_cast<double>(c.folds.size());
  model.v_validation_mae = v_sum / folds_n;
  model.w_validation_mae = w_sum / folds_n;
  model.v_kinematic_mae = vk_sum / folds_n;
  model.w_kinematic_mae = wk_sum / folds_n;
  if (progress) progress(total, total);
  s.train_windows = train[0].size();
  s.seconds = core::seconds_since(start);
  if (!model.IsValid(&why)) fail_selection("the trained model is unusable: " + why);
  if (summary) *summary = std::move(s);
  return model;
}

}  // namespace odotune::learned
