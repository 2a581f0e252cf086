#include <odotune/objectives/rl_bag_scores.h>

#include <span>
#include <utility>

#include <odotune/objectives/rl_protocols.h>

namespace odotune::objectives {

rlnode::ReplayOutput outage_run(const rlnode::Recording& rec, const rlnode::ReplaySettings& s,
                                std::int64_t from_ns, std::int64_t until_ns, bool trajectory) {
  return rlnode::replay(
      rec, rlnode::make_schedule(rec, outage_protocol_roles(rec, from_ns, until_ns), until_ns), s, trajectory);
}

namespace {

// Both protocols' scores, and the outage run's trajectory when asked.
std::pair<RlProtocolScores, std::vector<rlnode::TrajectoryPoint>> protocol_runs(
    const rlnode::Recording& rec, const rlnode::ReplaySettings& s, const RlJudgedSpan& span, bool trajectory) {
  rlnode::ReplayOutput a = outage_run(rec, s, span.outage_from_ns, span.end_ns, trajectory);
  const rlnode::ReplayOutput b = rlnode::replay(
      rec, rlnode::make_schedule(rec, every_fifth_roles(rec, span.fifth_from_ns, span.end_ns), span.end_ns), s);
  const RlProtocolScores scores{score_of(std::span(&a, 1)), score_of(std::span(&b, 1))};
  return {scores, std::move(a.trajectory)};
}

}  // namespace

RlProtocolScores score_protocols(const rlnode::Recording& rec, const rlnode::ReplaySettings& s,
                                 const RlJudgedSpan& span) {
  return protocol_runs(rec, s, span, false).first;
}

RlBagScores score_rl_bag(const rlnode::Recording& rec, const rlnode::ReplaySettings& s,
                         const RlBagEvalOptions& options) {
  const std::int64_t until = options.until_ns;
  RlBagScores out;
  out.run = rlnode::replay(rec, rlnode::make_schedule(rec, {}, until), s, options.keep_trajectory);
  for (const rlnode::GpsFix& f : rec.fixes)
    out.fixes.push_back({f.stamp_ns, rlnode::fix_in_odom(f, out.run.gps_transform)});
  if (rec.fixes.empty()) return out;
  std::vector<rlnode::Schedule> folds;
  for (const auto& roles : heldout_fix_folds(rec, options.folds, options.block_s, until))
    folds.push_back(rlnode::make_schedule(rec, roles, until));
  out.heldout = replay_score(rec, folds, s);
  if (options.from_ns) {
    auto [scores, trajectory] = protocol_runs(rec, s, {*options.from_ns, *options.from_ns, until},
                                              options.keep_trajectory);
    out.protocols = scores;
    out.outage_trajectory = std::move(trajectory);
  }
  if (!options.outage_s.empty()) {
    const std::int64_t first = options.from_ns ? *options.from_ns : after_warmup(rec, options.warmup_s);
    const std::vector<OutageWindow> w = outage_windows(rec, options.outage_s, options.outage_every_s, first,
                                                       until);
    out.outage_windows = w.size();
    out.outages = OutageReplays(rec, w, until).score(s);
  }
  return out;
}

}  // namespace odotune::objectives
