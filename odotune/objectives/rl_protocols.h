// Which GPS fixes a robot_localization replay fuses, withholds and scores:
// every protocol of the tune and of its judging, in one place. A role per
// Recording::fixes entry (rlnode::FixRole); a scored fix is withheld from the
// filter and its prediction at the fix's stamp compared with it.
//
//   held-out folds  K folds of time blocks before `until`: fold
//                   ⌊(t − t₀)/block⌋ mod K is scored, the others fused.
//   outage window   fused before its start, scored in [start, end), none after:
//                   a simulated GPS outage with the GPS fused before it.
//   outage protocol fused before `from`, every fix in [from, end) scored.
//   every fifth     fused before `from`; in [from, end) every 5th fix scored
//                   and the others fused.
//
// Times are the fixes' header stamps [ns]; t₀ is the first fix's.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <odotune/rlnode/recording.h>
#include <odotune/rlnode/replay.h>

namespace odotune::objectives {

std::vector<std::vector<rlnode::FixRole>> heldout_fix_folds(const rlnode::Recording& rec, int folds,
                                                            double block_s, std::int64_t until_ns);

struct OutageWindow {
  std::int64_t start_ns = 0, end_ns = 0;
};
// Windows of each length in `lengths_s`, starting every `stride_s` from
// `first_ns`, each ending by `until_ns` and by the last fix. Ordered by start,
// then in the order of `lengths_s`.
std::vector<OutageWindow> outage_windows(const rlnode::Recording& rec, std::span<const double> lengths_s,
                                         double stride_s, std::int64_t first_ns, std::int64_t until_ns);
// The first start that leaves the filter `warmup_s` of GPS: after the first fix.
std::int64_t after_warmup(const rlnode::Recording& rec, double warmup_s);
std::vector<rlnode::FixRole> outage_window_roles(const rlnode::Recording& rec, const OutageWindow& w);

std::vector<rlnode::FixRole> outage_protocol_roles(const rlnode::Recording& rec, std::int64_t from_ns,
                                                   std::int64_t end_ns);
std::vector<rlnode::FixRole> every_fifth_roles(const rlnode::Recording& rec, std::int64_t from_ns,
                                               std::int64_t end_ns);

}  // namespace odotune::objectives
