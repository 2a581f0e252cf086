#include <odotune/objectives/rl_protocols.h>

#include <algorithm>
#include <cmath>

namespace odotune::objectives {

using rlnode::FixRole;

std::vector<std::vector<FixRole>> heldout_fix_folds(const rlnode::Recording& rec, int folds, double block_s,
                                                    std::int64_t until_ns) {
  std::vector<std::vector<FixRole>> out(folds, std::vector<FixRole>(rec.fixes.size(), FixRole::fuse));
  if (rec.fixes.empty()) return out;
  const std::int64_t t0 = rec.fixes.front().stamp_ns;
  for (std::size_t i = 0; i < rec.fixes.size(); ++i) {
    if (rec.fixes[i].stamp_ns >= until_ns) continue;
    const auto block = static_cast<long>(
        std::floor(static_cast<double>(rec.fixes[i].stamp_ns - t0) * 1e-9 / block_s));
    out[block % folds][i] = FixRole::score;
  }
  return out;
}

namespace {

std::int64_t ns(double s) { return static_cast<std::int64_t>(std::llround(s * 1e9)); }

}  // namespace

std::int64_t after_warmup(const rlnode::Recording& rec, double warmup_s) {
  return rec.fixes.empty() ? rec.start_ns : rec.fixes.front().stamp_ns + ns(warmup_s);
}

std::vector<OutageWindow> outage_windows(const rlnode::Recording& rec, std::span<const double> lengths_s,
                                         double stride_s, std::int64_t first, std::int64_t until_ns) {
  std::vector<OutageWindow> out;
  if (rec.fixes.empty() || lengths_s.empty() || !(stride_s > 0.0)) return out;
  const std::int64_t end_by = std::min(until_ns, rec.fixes.back().stamp_ns + 1);
  const double shortest = *std::min_element(lengths_s.begin(), lengths_s.end());
  for (long k = 0;; ++k) {
    const std::int64_t start = first + ns(static_cast<double>(k) * stride_s);
    if (start + ns(shortest) > end_by) break;
    for (double length : lengths_s) {
      if (start + ns(length) <= end_by) out.push_back({start, start + ns(length)});
    }
  }
  return out;
}

std::vector<FixRole> outage_window_roles(const rlnode::Recording& rec, const OutageWindow& w) {
  std::vector<FixRole> roles(rec.fixes.size(), FixRole::fuse);
  for (std::size_t i = 0; i < rec.fixes.size(); ++i) {
    const std::int64_t t = rec.fixes[i].stamp_ns;
    if (t >= w.end_ns)
      roles[i] = FixRole::absent;
    else if (t >= w.start_ns)
      roles[i] = FixRole::score;
  }
  return roles;
}

std::vector<FixRole> outage_protocol_roles(const rlnode::Recording& rec, std::int64_t from_ns,
                                           std::int64_t end_ns) {
  std::vector<FixRole> roles(rec.fixes.size(), FixRole::fuse);
  for (std::size_t i = 0; i < rec.fixes.size(); ++i) {
    const std::int64_t t = rec.fixes[i].stamp_ns;
    if (t >= end_ns)
      roles[i] = FixRole::absent;
    else if (t >= from_ns)
      roles[i] = FixRole::score;
  }
  return roles;
}

std::vector<FixRole> every_fifth_roles(const rlnode::Recording& rec, std::int64_t from_ns,
                                       std::int64_t end_ns) {
  std::vector<FixRole> roles(rec.fixes.size(), FixRole::fuse);
  int k = 0;
  for (std::size_t i = 0; i < rec.fixes.size(); ++i) {
    const std::int64_t t = rec.fixes[i].stamp_ns;
    if (t >= end_ns)
      roles[i] = FixRole::absent;
    else if (t >= from_ns)
      roles[i] = k++ % 5 == 0 ? FixRole::score : FixRole::fuse;
  }
  return roles;
}

}  // namespace odotune::objectives
