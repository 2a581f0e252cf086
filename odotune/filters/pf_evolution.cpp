#include <odotune/filters/pf_evolution.h>

#include <algorithm>
#include <cmath>

#include <odotune/core/why.h>

namespace odotune::filters {

bool EvidenceMemoryParams::IsValid(std::string* why) const {
  auto positive = [](double x) { return std::isfinite(x) && x > 0.0; };
  if (positive(min_memory_s) && positive(max_memory_s) && max_memory_s >= min_memory_s) return true;
  return core::invalid(why, "min_memory_s = " + std::to_string(min_memory_s) + ", max_memory_s = " +
                                std::to_string(max_memory_s) + " must be finite with 0 < min ≤ max [s]");
}

double EvidenceMemory::step(double dt_s) {
  if (!(dt_s > 0.0)) return 0.0;
  const double inflate = std::expm1(dt_s / memory_s_);
  memory_s_ = std::min(memory_s_ + dt_s, p_.max_memory_s);
  return inflate;
}

}  // namespace odotune::filters
