// Validation of an Options struct as a table of rules, so each IsValid reads
// as the list of its constraints and words its message the same way:
// "NAME = VALUE must be EXPECTED".
#pragma once

#include <cmath>
#include <initializer_list>
#include <string>

#include <fmt/format.h>

#include <odotune/core/why.h>

namespace odotune::diagnose {

struct OptionRule {
  bool ok;
  const char* name;
  double value;
  const char* expected;
};

// False (with the first broken rule in *why) when a rule does not hold.
inline bool check_option_rules(std::initializer_list<OptionRule> rules, std::string* why) {
  for (const OptionRule& r : rules) {
    if (r.ok) continue;
    return core::invalid(why, fmt::format("{} = {} must be {}", r.name, r.value, r.expected));
  }
  return true;
}

inline bool is_positive(double v) { return std::isfinite(v) && v > 0; }
inline bool is_non_negative(double v) { return std::isfinite(v) && v >= 0; }
inline bool is_fraction(double v) { return is_non_negative(v) && v <= 1; }

}  // namespace odotune::diagnose
