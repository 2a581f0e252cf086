// robot_localization's filter on a robot's own recording, scored without
// ground truth by its GPS fixes (which fixes each protocol fuses and scores:
// odotune/objectives/rl_protocols.h): what `odotune eval --rl-params P --bag B`
// reports, and the two protocols a tune is judged by on a span it never saw.
// Each function replays and scores in one call; nothing is kept between calls.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include <odotune/objectives/rl_objective.h>
#include <odotune/rlnode/recording.h>
#include <odotune/rlnode/replay.h>

namespace odotune::objectives {

// The two protocols on one span.
struct RlProtocolScores {
  FixScore outage, every_fifth;
};
// A span and its two protocols: a GPS outage from `outage_from_ns` to
// `end_ns` (the GPS fused before), and every 5th fix of [fifth_from_ns,
// end_ns) held out (the others fused). Stamps, absolute [ns].
struct RlJudgedSpan {
  std::int64_t outage_from_ns = 0, fifth_from_ns = 0, end_ns = 0;
};

// The outage protocol's run: GPS fused before `from_ns` only, every fix from
// there to `until_ns` scored (its `scored`: measured and predicted, odom
// frame), the recording cut at `until_ns`; with `trajectory`, the filter's
// trajectory too (scoring a fix leaves the filter as it is, so it is the
// trajectory of GPS fused before `from_ns` only).
rlnode::ReplayOutput outage_run(const rlnode::Recording& rec, const rlnode::ReplaySettings& s,
                                std::int64_t from_ns, std::int64_t until_ns, bool trajectory = false);
// Both protocols of `span` under `s`.
RlProtocolScores score_protocols(const rlnode::Recording& rec, const rlnode::ReplaySettings& s,
                                 const RlJudgedSpan& span);

// What score_rl_bag replays and scores. Times are stamps, absolute [ns].
struct RlBagEvalOptions {
  std::int64_t until_ns = std::numeric_limits<std::int64_t>::max();  // the recording cut here
  // Both protocols on [from_ns, until_ns) (RlJudgedSpan{from_ns, from_ns,
  // until_ns}), and the first simulated outage's start; nullopt: no protocols.
  std::optional<std::int64_t> from_ns;
  int folds = 5;         // held-out fixes over the span: folds of
  double block_s = 1.0;  // time blocks this long [s]
  // Simulated outages of these lengths [s] (empty: none), one of each starting
  // every outage_every_s from from_ns, or warmup_s after the first fix.
  std::vector<double> outage_s;
  double outage_every_s = 10.0, warmup_s = 30.0;
  bool keep_trajectory = false;  // the run's trajectory, and the outage protocol's
};

// A fix as navsat_transform_node placed it under the run's transform.
struct RlPlacedFix {
  std::int64_t stamp_ns = 0;
  Eigen::Vector3d odom = Eigen::Vector3d::Zero();  // [m], odom frame
};

struct RlBagScores {
  rlnode::ReplayOutput run;        // every fix fused until until_ns
  std::vector<RlPlacedFix> fixes;  // every fix of the recording, under run.gps_transform
  // On a recording with fixes:
  std::optional<FixScore> heldout;            // the held-out folds
  std::optional<RlProtocolScores> protocols;  // with from_ns
  // The outage protocol's trajectory (with from_ns and keep_trajectory).
  std::vector<rlnode::TrajectoryPoint> outage_trajectory;
  std::optional<FixScore> outages;  // with outage_s: every window's fixes together
  std::size_t outage_windows = 0;
};
RlBagScores score_rl_bag(const rlnode::Recording& rec, const rlnode::ReplaySettings& s,
                         const RlBagEvalOptions& options);

}  // namespace odotune::objectives
