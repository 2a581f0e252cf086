// The groups of position fixes that the pose-domain fits dead-reckon over
// (pose_calibration.h, twist_calibration.h): consecutive fixes spanning less
// than segment_s (0: all of them), each group at least min_fixes long (a
// start pose has three unknowns), a short tail joined to the group before.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

namespace odotune::calibration {

// [first, last] indices into fix_t (increasing times [s]); a group shorter
// than min_fixes remains only when all the fixes are fewer (callers skip it).
inline std::vector<std::pair<std::size_t, std::size_t>> fix_groups(const std::vector<double>& fix_t,
                                                                   double segment_s, std::size_t min_fixes) {
  const std::size_t m = fix_t.size();
  std::vector<std::pair<std::size_t, std::size_t>> groups;
  for (std::size_t b = 0; b < m;) {
    std::size_t e = b;
    while (e + 1 < m && (segment_s <= 0.0 || fix_t[e + 1] - fix_t[b] < segment_s)) ++e;
    while (e + 1 < m && e - b + 1 < min_fixes) ++e;
    groups.emplace_back(b, e);
    b = e + 1;
  }
  if (groups.size() > 1 && groups.back().second - groups.back().first + 1 < min_fixes) {
    groups[groups.size() - 2].second = groups.back().second;
    groups.pop_back();
  }
  return groups;
}

}  // namespace odotune::calibration
