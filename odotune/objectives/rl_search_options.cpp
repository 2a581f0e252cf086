#include <odotune/objectives/rl_search_options.h>

#include <cmath>

#include <fmt/format.h>

#include <odotune/core/why.h>

namespace odotune::objectives {

bool RlSearchOptions::IsValid(std::string* why) const {
  for (double l : grid_levels)
    if (!std::isfinite(l)) return core::invalid(why, "a grid level is not finite");
  if (!(refine_decades >= 0.0))
    return core::invalid(why, fmt::format("refine_decades {}, expected ≥ 0", refine_decades));
  if (!(profile_step_decades > 0.0))
    return core::invalid(why, fmt::format("profile step {} decades, expected > 0", profile_step_decades));
  if (!(tolerance > 0.0 && tolerance < 1.0))
    return core::invalid(why, fmt::format("tolerance {}, expected in (0, 1)", tolerance));
  return true;
}

}  // namespace odotune::objectives
