#include <odotune/objectives/rl_objective.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <odotune/core/enum_names.h>
#include <odotune/core/why.h>
#include <odotune/objectives/rl_innovations.h>

namespace odotune::objectives {
namespace {

namespace rl = filters::rl;
using rlnode::FixRole;

// The state members two_d_mode measures as zero: not worth searching there.
bool forced_in_2d(int m) {
  return m == rl::kZ || m == rl::kRoll || m == rl::kPitch || m == rl::kVz || m == rl::kVroll ||
         m == rl::kVpitch || m == rl::kAz;
}

constexpr const char* kMemberNames[rl::kStateSize] = {
    "x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz", "vroll", "vpitch", "vyaw", "ax", "ay", "az"};

constexpr const char* kBlockNames[5] = {"position", "orientation", "linear_velocity", "angular_velocity",
                                        "acceleration"};

// A penalty the solvers rank below every real score.
constexpr double kDiverged = 1e9;

}  // namespace

bool parse_rl_fitness(std::string_view text, RlFitness* out) {
  return core::parse_by_name(text, kAllRlFitnesses, out);
}

bool parse_rl_noise_space(std::string_view text, RlNoiseSpace* out) {
  return core::parse_by_name(text, kAllRlNoiseSpaces, out);
}

int stored_mode(RlFitness f) {
  switch (f) {
    case RlFitness::heldout_fixes: return kRlHeldoutFixesMode;
    case RlFitness::outage: return kRlOutageMode;
    case RlFitness::both: return kRlBothMode;
    case RlFitness::innovation_nll: return kRlInnovationNllMode;
    case RlFitness::nis: return kRlNisMode;
    case RlFitness::whiteness: return kRlWhitenessMode;
    case RlFitness::heldout_nll: return kRlHeldoutNllMode;
  }
  return 0;
}

std::optional<RlFitness> rl_fitness_of_mode(int mode) {
  for (RlFitness f : {RlFitness::heldout_fixes, RlFitness::outage, RlFitness::both, RlFitness::innovation_nll,
                      RlFitness::nis, RlFitness::whiteness, RlFitness::heldout_nll})
    if (stored_mode(f) == mode) return f;
  return std::nullopt;
}

std::vector<std::string> rl_noise_parameter_names(RlNoiseSpace space, bool two_d) {
  std::vector<std::string> names;
  if (space == RlNoiseSpace::diagonal) {
    for (int m = 0; m < rl::kStateSize; ++m)
      if (!(two_d && forced_in_2d(m))) names.push_back(fmt::format("q_{}", kMemberNames[m]));
  } else {
    for (const char* b : kBlockNames) names.push_back(fmt::format("q_{}", b));
  }
  return names;
}

std::vector<int> rl_noise_members(std::string_view name, bool two_d) {
  for (int m = 0; m < rl::kStateSize; ++m)
    if (name == fmt::format("q_{}", kMemberNames[m])) return {m};
  for (int b = 0; b < 5; ++b) {
    if (name != fmt::format("q_{}", kBlockNames[b])) continue;
    std::vector<int> members;
    for (int m = 3 * b; m < 3 * b + 3; ++m)
      if (!(two_d && forced_in_2d(m))) members.push_back(m);
    return members;
  }
  return {};
}

filters::rl::UkfConstants scaled_ukf_constants(const filters::rl::UkfConstants& base, double alpha_factor,
                                               double n_plus_kappa_factor, double beta_factor) {
  constexpr double n = filters::rl::kStateSize;
  // A factor of 1 leaves kappa's bits alone ((n + κ)·1 − n may round).
  const double kappa = n_plus_kappa_factor == 1.0 ? base.kappa : (n + base.kappa) * n_plus_kappa_factor - n;
  return {base.alpha * alpha_factor, kappa, base.beta * beta_factor};
}

bool apply_rl_factors(const rlnode::RlParams& params, std::span<const std::string> names,
                      std::span<const double> factors, rlnode::ReplaySettings* s, std::string* why) {
  const rlnode::ReplaySettings base = *s;
  std::array<double, 3> ukf_factors = {1.0, 1.0, 1.0};
  for (std::size_t i = 0; i < names.size() && i < factors.size(); ++i) {
    if (!(factors[i] > 0.0 && std::isfinite(factors[i]))) {
      return core::invalid(why, fmt::format("{} = {}: expected a positive factor", names[i], factors[i]));
    }
    const auto ukf = std::find(kUkfFactorNames.begin(), kUkfFactorNames.end(), names[i]);
    if (ukf != kUkfFactorNames.end()) {
      if (params.filter != filters::rl::RlFilterType::ukf) {
        return core::invalid(why, fmt::format("'{}' is ukf_node's, and this file runs ekf_node", names[i]));
      }
      ukf_factors[static_cast<std::size_t>(ukf - kUkfFactorNames.begin())] = factors[i];
      continue;
    }
    const std::vector<int> members = rl_noise_members(names[i], params.two_d_mode);
    for (int m : members) s->process_noise(m, m) = base.process_noise(m, m) * factors[i];
    if (!members.empty()) continue;
    bool found = false;
    for (std::size_t k = 0; k < params.sensors.size() && !found; ++k) {
      if (names[i] != "cov_" + params.sensors[k].name) continue;
      s->covariance_scale[k] = base.covariance_scale[k] * factors[i];
      found = true;
    }
    if (!found) {
      return core::invalid(why, fmt::format("'{}' is not a parameter of this file's filter", names[i]));
    }
  }
  if (names.size() != factors.size()) {
    return core::invalid(why, fmt::format("{} names for {} factors", names.size(), factors.size()));
  }
  s->ukf = scaled_ukf_constants(base.ukf, ukf_factors[0], ukf_factors[1], ukf_factors[2]);
  return true;
}

std::string_view to_string(RlFitness f) {
  switch (f) {
    case RlFitness::heldout_fixes: return "heldout-fixes";
    case RlFitness::outage: return "outage";
    case RlFitness::both: return "both";
    case RlFitness::innovation_nll: return "innovation-nll";
    case RlFitness::nis: return "nis";
    case RlFitness::whiteness: return "whiteness";
    case RlFitness::heldout_nll: return "heldout-nll";
  }
  return "";
}

std::string_view to_string(RlNoiseSpace s) {
  switch (s) {
    case RlNoiseSpace::diagonal: return "diagonal";
    case RlNoiseSpace::blocks: return "blocks";
  }
  return "";
}

bool RlTuneOptions::IsValid(std::string* why) const {
  if (folds < 2) return core::invalid(why, fmt::format("folds = {}, expected at least 2", folds));
  if (!(block_s > 0.0)) return core::invalid(why, fmt::format("block_s = {}, expected > 0", block_s));
  if (outage_s.empty()) return core::invalid(why, "no outage length; expected at least one");
  for (double l : outage_s)
    if (!(l > 0.0)) return core::invalid(why, fmt::format("outage length {} s, expected > 0", l));
  if (!(outage_stride_s > 0.0))
    return core::invalid(why, fmt::format("outage stride {} s, expected > 0", outage_stride_s));
  if (!(warmup_s >= 0.0)) return core::invalid(why, fmt::format("warm-up {} s, expected ≥ 0", warmup_s));
  if (!(prior_weight >= 0.0 && std::isfinite(prior_weight)))
    return core::invalid(why, fmt::format("prior weight {}, expected a finite value ≥ 0", prior_weight));
  if (!(decades_down >= 0.0 && decades_up >= 0.0 && decades_down + decades_up > 0.0)) {
    return core::invalid(why, fmt::format("decades {} down, {} up: expected ≥ 0 and a non-empty range",
                                          decades_down, decades_up));
  }
  return true;
}

namespace {

// The held-out fixes' errors added up, output by output (in one order, so
// that a batch sums as its single replays do).
struct ScoreSum {
  FixScore s;
  double sum = 0.0, sum_abs = 0.0, sum_var = 0.0;
  void add(const rlnode::ReplayOutput& o) {
    s.finite = s.finite && o.finite;
    for (const rlnode::ScoredFix& f : o.scored) {
      const double e = (f.predicted - f.measured).head<2>().norm();
      sum += e * e;
      sum_abs += e;
      sum_var += f.fix_cov.trace();
      s.maxe_m = std::max(s.maxe_m, e);
    }
    s.fixes += static_cast<long>(o.scored.size());
  }
  FixScore done() const {
    FixScore out = s;
    const double n = static_cast<double>(s.fixes);
    out.rmse_m = s.fixes > 0 ? std::sqrt(sum / n) : std::numeric_limits<double>::quiet_NaN();
    out.mae_m = s.fixes > 0 ? sum_abs / n : std::numeric_limits<double>::quiet_NaN();
    out.fix_var_m2 = s.fixes > 0 ? sum_var / n : 0.0;
    if (!std::isfinite(out.rmse_m)) out.finite = false;
    return out;
  }
};

}  // namespace

double error_without_fix_noise_m(const FixScore& s) {
  return std::sqrt(std::max(s.rmse_m * s.rmse_m - s.fix_var_m2, 0.0));
}

FixScore score_of(std::span<const rlnode::ReplayOutput> outputs) {
  ScoreSum sum;
  for (const rlnode::ReplayOutput& o : outputs) sum.add(o);
  return sum.done();
}

FixScore replay_score(const rlnode::Recording& rec, std::span<const rlnode::Schedule> schedules,
                      const rlnode::ReplaySettings& s) {
  std::vector<rlnode::ReplayOutput> outs;
  outs.reserve(schedules.size());
  for (const rlnode::Schedule& schedule : schedules) outs.push_back(rlnode::replay(rec, schedule, s));
  return score_of(outs);
}

std::vector<FixScore> replay_score_batch(const rlnode::Recording& rec,
                                         std::span<const rlnode::Schedule> schedules,
                                         std::span<const rlnode::ReplaySettings> settings) {
  std::vector<ScoreSum> sums(settings.size());
  for (const rlnode::Schedule& schedule : schedules) {
    const std::vector<rlnode::ReplayOutput> outs = rlnode::replay_batch(rec, schedule, settings);
    for (std::size_t k = 0; k < outs.size(); ++k) sums[k].add(outs[k]);
  }
  std::vector<FixScore> out;
  out.reserve(sums.size());
  for (const ScoreSum& s : sums) out.push_back(s.done());
  return out;
}

OutageReplays::OutageReplays(const rlnode::Recording& rec, std::span<const OutageWindow> windows,
                             std::int64_t until_ns)
    : rec_(&rec), fused_(rlnode::make_schedule(rec, {}, until_ns)) {
  for (const OutageWindow& w : windows) {
    rlnode::Schedule own = rlnode::make_schedule(rec, outage_window_roles(rec, w),
                                                 std::min(w.end_ns, until_ns));
    const auto& a = fused_.events;
    const auto& b = own.events;
    std::size_t k = 0;
    while (k < a.size() && k < b.size() && a[k].type == b[k].type && a[k].input == b[k].input &&
           a[k].time_ns == b[k].time_ns)
      ++k;
    tails_.push_back({k, std::vector<rlnode::Event>(b.begin() + static_cast<std::ptrdiff_t>(k), b.end()), w});
  }
  std::stable_sort(tails_.begin(), tails_.end(),
                   [](const Tail& x, const Tail& y) { return x.shared < y.shared; });
}

FixScore OutageReplays::score(const rlnode::ReplaySettings& s) const {
  ScoreSum sum;
  each_window(
      s, [&](const OutageWindow&, const rlnode::ReplayOutput& o) { sum.add(o); }, false);
  return sum.done();
}

void OutageReplays::each_window(const rlnode::ReplaySettings& s,
                                const std::function<void(const OutageWindow&, const rlnode::ReplayOutput&)>& f,
                                bool keep_trajectory) const {
  rlnode::Replayer fused(*rec_, s);
  std::size_t done = 0;
  for (const Tail& t : tails_) {
    fused.run(std::span(fused_.events).subspan(done, t.shared - done));
    done = t.shared;
    rlnode::Replayer window = fused;
    window.run(t.events, keep_trajectory);
    f(t.window, std::move(window).finish());
  }
}

std::vector<FixScore> OutageReplays::score_batch(std::span<const rlnode::ReplaySettings> settings) const {
  const bool all_lockstep = std::all_of(settings.begin(), settings.end(), [&](const rlnode::ReplaySettings& s) {
    return rlnode::lockstep(*rec_, s);
  });
  if (!all_lockstep) {  // the lanes run the EKF without use_control only: the others one by one
    std::vector<FixScore> out;
    for (const rlnode::ReplaySettings& s : settings) out.push_back(score(s));
    return out;
  }
  std::vector<ScoreSum> sums(settings.size());
  for (std::size_t k0 = 0; k0 < settings.size(); k0 += filters::rl::kLanes) {
    const std::size_t lanes = std::min<std::size_t>(filters::rl::kLanes, settings.size() - k0);
    rlnode::BatchReplayer fused(*rec_, settings.subspan(k0, lanes));
    std::size_t done = 0;
    for (const Tail& t : tails_) {
      fused.run(std::span(fused_.events).subspan(done, t.shared - done));
      done = t.shared;
      rlnode::BatchReplayer window = fused;
      window.run(t.events);
      std::vector<rlnode::ReplayOutput> outs;
      std::move(window).finish(outs);
      for (std::size_t l = 0; l < outs.size(); ++l) sums[k0 + l].add(outs[l]);
    }
  }
  std::vector<FixScore> out;
  out.reserve(sums.size());
  for (const ScoreSum& s : sums) out.push_back(s.done());
  return out;
}

namespace detail {

RmsPart pooled_parts(std::span<const RmsPart> parts) {
  RmsPart out;
  double sq = 0.0, abs = 0.0, mean = 0.0;
  for (const RmsPart& p : parts) {
    if (p.n == 0) continue;
    const auto n = static_cast<double>(p.n);
    out.finite = out.finite && p.finite;
    sq += p.rmse * p.rmse * n;
    abs += p.mae * n;
    mean += p.mean * n;
    out.max = std::max(out.max, p.max);
    out.n += p.n;
  }
  const auto n = static_cast<double>(out.n);
  out.rmse = out.n > 0 ? std::sqrt(sq / n) : std::numeric_limits<double>::quiet_NaN();
  out.mae = out.n > 0 ? abs / n : std::numeric_limits<double>::quiet_NaN();
  out.mean = out.n > 0 ? mean / n : 0.0;
  if (!std::isfinite(out.rmse)) out.finite = false;
  return out;
}

}  // namespace detail

FixScore pooled(std::span<const FixScore> scores) {
  if (scores.size() == 1) return scores.front();
  std::vector<detail::RmsPart> parts;
  for (const FixScore& f : scores) {
    parts.push_back({.n = f.fixes,
                     .rmse = f.rmse_m,
                     .mae = f.mae_m,
                     .max = f.maxe_m,
                     .finite = f.finite,
                     .mean = f.fix_var_m2});
  }
  const detail::RmsPart p = detail::pooled_parts(parts);
  return {.rmse_m = p.rmse,
          .mae_m = p.mae,
          .maxe_m = p.max,
          .fixes = p.n,
          .finite = p.finite,
          .fix_var_m2 = p.mean};
}

RlObjective::RlObjective(const rlnode::Recording& rec, const rlnode::ReplaySettings& base,
                         const RlTuneOptions& options)
    : RlObjective(std::vector<const rlnode::Recording*>{&rec}, base, options) {}

RlObjective::RlObjective(std::span<const rlnode::Recording* const> recs, rlnode::ReplaySettings base,
                         const RlTuneOptions& options)
    : base_(std::move(base)), options_(options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("rl tune: " + why);
  if (recs.empty()) throw std::invalid_argument("rl tune: no recording");
  if (recs.size() > 1 && statistic_kind()) {
    throw std::invalid_argument(
        fmt::format("rl tune: --fitness {} takes one recording; expected heldout-fixes, "
                    "outage or both for {} recordings",
                    to_string(options.fitness), recs.size()));
  }
  const rlnode::Recording& rec = *recs.front();
  for (const rlnode::Recording* r : recs) {
    if (r->fixes.empty()) {
      throw std::invalid_argument(
          fmt::format("{}: no GPS fixes to score the filter by; expected a NavSatFix topic "
                      "fused through navsat_transform_node's output (or a track's position fixes)",
                      r->bag.string()));
    }
  }
  std::vector<ParamSpec> specs;
  const double lo = std::pow(10.0, -options.decades_down), hi = std::pow(10.0, options.decades_up);
  auto add_noise = [&](std::string name, std::vector<int> members, std::string meaning) {
    specs.push_back({std::move(name), "×", lo, hi, true, std::move(meaning)});
    noise_members_.push_back(std::move(members));
  };
  for (const std::string& name : rl_noise_parameter_names(options.space, rec.params.two_d_mode)) {
    add_noise(name, rl_noise_members(name, rec.params.two_d_mode),
              options.space == RlNoiseSpace::diagonal ? "factor on process_noise_covariance's diagonal entry"
                                                      : "factor on a block of process_noise_covariance");
  }
  if (options.input_covariances) {
    for (std::size_t s = 0; s < rec.params.sensors.size(); ++s) {
      specs.push_back({"cov_" + rec.params.sensors[s].name, "×", lo, hi, true,
                       "factor on the input's message covariance"});
      cov_sensors_.push_back(static_cast<int>(s));
    }
  }
  if (options.ukf_constants) {
    if (rec.params.filter != filters::rl::RlFilterType::ukf) {
      throw std::invalid_argument(fmt::format(
          "{}: alpha, kappa and beta are ukf_node's, and the file runs ekf_node; expected a UKF file or --filter ukf",
          rec.params.file.string()));
    }
    // alpha in [1e-3, 1e3] × the file's, n + kappa and beta in [0.1, 10] ×.
    specs.push_back({std::string(kUkfFactorNames[0]), "×", 1e-3, 1e3, true, "factor on ukf_node's alpha"});
    specs.push_back({std::string(kUkfFactorNames[1]), "×", 0.1, 10.0, true, "factor on 15 + ukf_node's kappa"});
    specs.push_back({std::string(kUkfFactorNames[2]), "×", 0.1, 10.0, true, "factor on ukf_node's beta"});
  }
  space_ = BoxSpace(std::move(specs));

  for (const rlnode::Recording* r : recs) {
    Replays& p = recs_.emplace_back();
    p.rec = r;
    for (const auto& roles : heldout_fix_folds(*r, options.folds, options.block_s, options.until_ns))
      p.heldout.push_back(rlnode::make_schedule(*r, roles, options.until_ns));
    const std::vector<OutageWindow> windows = outage_windows(
        *r, options.outage_s, options.outage_stride_s, after_warmup(*r, options.warmup_s), options.until_ns);
    p.outages = OutageReplays(*r, windows, options.until_ns);
    p.fused = rlnode::make_schedule(*r, {}, options.until_ns);
  }
  base_parts_ = parts(base_);
  base_parts_.heldout = heldout_score(base_);
  base_parts_.outage = outage_score(base_);
  check_base_scores(rec);
}

void RlObjective::check_base_scores(const rlnode::Recording& rec) const {
  const std::string no_fix_scored = fmt::format(
      "{}: no fix is scored before the tuning span ends (outages of {} s after {} s of GPS); "
      "expected a longer span or shorter outages",
      recs_.size() > 1 ? fmt::format("all {} recordings", recs_.size()) : rec.bag.string(),
      fmt::join(options_.outage_s, ", "), options_.warmup_s);
  // Without a window the outage score is empty, not diverged.
  if (outage_needed() && window_count() == 0) throw std::invalid_argument(no_fix_scored);
  const bool heldout_used = heldout_needed() || options_.fitness == RlFitness::heldout_nll;
  for (const auto& [used, score, what] : {std::tuple{heldout_used, &base_parts_.heldout, "held-out fixes"},
                                          std::tuple{outage_needed(), &base_parts_.outage, "outages"}}) {
    if (used && std::isnan(score->rmse_m)) {
      throw std::invalid_argument(fmt::format(
          "{}: the file's own {}_node diverges on this recording (its state stops being finite in the {} "
          "replays), so there is nothing to tune from; expected a filter that follows the recording{}",
          rec.bag.string(), filters::rl::to_string(rec.params.filter), what,
          rec.params.filter == filters::rl::RlFilterType::ukf
              ? " (the UKF's heading mean fails once an unmeasured heading's variance passes 2 rad²)"
              : ""));
    }
  }
  if ((heldout_used && !(base_parts_.heldout.rmse_m > 0.0)) ||
      (outage_needed() && !(base_parts_.outage.rmse_m > 0.0)))
    throw std::invalid_argument(no_fix_scored);
  // With the fixes' variance taken out, each part used must keep some error to score.
  for (const FixScore* s :
       {heldout_used ? &base_parts_.heldout : nullptr, outage_needed() ? &base_parts_.outage : nullptr}) {
    if (s == nullptr || !options_.subtract_fix_variance || error_m(*s) > 0.0) continue;
    throw std::invalid_argument(fmt::format(
        "{}: the fixes' variances (mean var_x + var_y {:.4g} m²) exceed the file's squared error at them "
        "({:.4g} m²); expected variances that describe the fixes, or a tune without --subtract-fix-variance",
        rec.bag.string(), s->fix_var_m2, s->rmse_m * s->rmse_m));
  }
}

FixScore RlObjective::heldout_score(const rlnode::ReplaySettings& s) const {
  std::vector<FixScore> each;
  for (const Replays& p : recs_) each.push_back(replay_score(*p.rec, p.heldout, s));
  return pooled(each);
}

FixScore RlObjective::outage_score(const rlnode::ReplaySettings& s) const {
  std::vector<FixScore> each;
  for (const Replays& p : recs_) each.push_back(p.outages.score(s));
  return pooled(each);
}

std::size_t RlObjective::window_count() const {
  std::size_t n = 0;
  for (const Replays& p : recs_) n += p.outages.windows();
  return n;
}

rlnode::ReplaySettings RlObjective::settings_at(std::span<const double> x) const {
  const std::vector<double> v = space_.to_physical(x);
  rlnode::ReplaySettings s = base_;
  std::size_t k = 0;
  for (const std::vector<int>& members : noise_members_) {
    for (int m : members) s.process_noise(m, m) = base_.process_noise(m, m) * v[k];
    ++k;
  }
  for (int sensor : cov_sensors_) s.covariance_scale[sensor] = base_.covariance_scale[sensor] * v[k++];
  if (options_.ukf_constants) s.ukf = scaled_ukf_constants(base_.ukf, v[k], v[k + 1], v[k + 2]);
  return s;
}

bool RlObjective::heldout_needed() const {
  return options_.fitness == RlFitness::heldout_fixes || options_.fitness == RlFitness::both ||
         options_.keep_heldout;
}

bool RlObjective::outage_needed() const {
  return options_.fitness == RlFitness::outage || options_.fitness == RlFitness::both;
}

bool RlObjective::statistic_kind() const {
  return !outage_needed() && options_.fitness != RlFitness::heldout_fixes;
}

RlObjective::Parts RlObjective::parts(const rlnode::ReplaySettings& s) const {
  Parts p;
  if (heldout_needed() && options_.fitness != RlFitness::heldout_nll) p.heldout = heldout_score(s);
  if (outage_needed()) p.outage = outage_score(s);
  if (!statistic_kind()) return p;
  rlnode::ReplaySettings with = s;
  with.innovations = true;
  const Replays& one = recs_.front();
  if (options_.fitness == RlFitness::heldout_nll) {
    std::vector<rlnode::ReplayOutput> outs;
    for (const rlnode::Schedule& schedule : one.heldout)
      outs.push_back(rlnode::replay(*one.rec, schedule, with));
    p.heldout = score_of(outs);
    p.statistic = heldout_nll(outs);
    return p;
  }
  const rlnode::ReplayOutput out = rlnode::replay(*one.rec, one.fused, with);
  p.statistic = options_.fitness == RlFitness::innovation_nll ? innovation_nll(out.innovations)
                : options_.fitness == RlFitness::nis          ? nis_cost(out.innovations)
                                                              : whiteness_cost(out.innovations);
  if (!out.finite) p.statistic = std::numeric_limits<double>::quiet_NaN();
  return p;
}

double RlObjective::combine(const Parts& p) const {
  if (statistic_kind()) return std::isfinite(p.statistic) ? p.statistic : kDiverged;
  const bool both = options_.fitness == RlFitness::both;
  double f = 0.0;
  if (options_.fitness != RlFitness::outage) {
    if (!p.heldout.finite) return kDiverged;
    f += both ? error_m(p.heldout) / error_m(base_parts_.heldout) : error_m(p.heldout);
  }
  if (options_.fitness != RlFitness::heldout_fixes) {
    if (!p.outage.finite) return kDiverged;
    f += both ? error_m(p.outage) / error_m(base_parts_.outage) : error_m(p.outage);
  }
  return f;
}

double RlObjective::error_m(const FixScore& s) const {
  return options_.subtract_fix_variance ? error_without_fix_noise_m(s) : s.rmse_m;
}

double RlObjective::fitness_of(const Parts& p) const {
  double f = combine(p);
  // Worse than the file at held-out fixes: ranked above the file's own
  // fitness, by how much worse (an innovation statistic may be negative:
  // then above it by the excess in its own scale).
  if (f < kDiverged && options_.keep_heldout) {
    const double excess = error_m(p.heldout) / error_m(base_parts_.heldout) - 1.0;
    if (!p.heldout.finite) {
      f = kDiverged;
    } else if (excess > 0.0) {
      const double base = baseline_fitness();
      f = std::max(f, base) + (std::abs(base) + 1.0) * 10.0 * excess;
    }
  }
  if (f >= kDiverged) diverged_->fetch_add(1, std::memory_order_relaxed);
  return f;
}

double RlObjective::data_fitness(std::span<const double> x) const { return fitness_of(parts(settings_at(x))); }

void RlObjective::data_fitness_batch(std::span<const double> xs, std::span<double> out) const {
  const std::size_t dim = space_.dim();
  if (statistic_kind()) {
    for (std::size_t k = 0; k < out.size(); ++k) out[k] = data_fitness(xs.subspan(k * dim, dim));
    return;
  }
  std::vector<rlnode::ReplaySettings> settings;
  for (std::size_t k = 0; k < out.size(); ++k) settings.push_back(settings_at(xs.subspan(k * dim, dim)));
  // Per lane, each recording's score, then pooled as the single calls pool them.
  std::vector<std::vector<FixScore>> heldout(out.size()), outage(out.size());
  for (const Replays& p : recs_) {
    const std::vector<FixScore> h = heldout_needed() ? replay_score_batch(*p.rec, p.heldout, settings)
                                                     : std::vector<FixScore>(out.size());
    const std::vector<FixScore> o = outage_needed() ? p.outages.score_batch(settings)
                                                    : std::vector<FixScore>(out.size());
    for (std::size_t k = 0; k < out.size(); ++k) {
      heldout[k].push_back(h[k]);
      outage[k].push_back(o[k]);
    }
  }
  for (std::size_t k = 0; k < out.size(); ++k)
    out[k] = fitness_of({pooled(heldout[k]), pooled(outage[k]), 0.0});
}

double RlObjective::prior(std::span<const double> x) const {
  if (!(options_.prior_weight > 0.0)) return 0.0;
  double sum = 0.0;
  for (double v : space_.to_physical(x)) sum += std::log10(v) * std::log10(v);
  return options_.prior_weight * sum / static_cast<double>(x.size());
}

double RlObjective::fitness(std::span<const double> x) const {
  const double f = data_fitness(x);
  return f < kDiverged ? f + prior(x) : f;
}

void RlObjective::fitness_batch(std::span<const double> xs, std::span<double> out) const {
  data_fitness_batch(xs, out);
  const std::size_t dim = space_.dim();
  for (std::size_t k = 0; k < out.size(); ++k)
    if (out[k] < kDiverged) out[k] += prior(xs.subspan(k * dim, dim));
}

}  // namespace odotune::objectives
