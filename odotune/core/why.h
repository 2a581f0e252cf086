// The failure half of the IsValid(std::string* why) convention (Ceres'
// Options::IsValid): writes the reason when asked for it and returns false,
// so a check reads `if (bad) return invalid(why, "…");`.
#pragma once

#include <string>
#include <utility>

namespace odotune::core {

inline bool invalid(std::string* why, std::string message) {
  if (why) *why = std::move(message);
  return false;
}

}  // namespace odotune::core
