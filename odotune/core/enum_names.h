// Parsing an enum from the names its to_string gives (Ceres' pairing of
// XToString and StringToX): one loop for every enum instead of one per enum,
// so a parse is always the inverse of its to_string. Works for any value type
// with a to_string found by argument-dependent lookup (e.g.
// objectives::TunedModel), over a braced list or any range of its values
// (an enum's kAll… array, so that the parse, the --help text and the error
// messages list the same values).
#pragma once

#include <initializer_list>
#include <string>
#include <string_view>

namespace odotune::core {

// Sets *out to the value of `values` whose to_string(value) is `text`;
// false (and *out unchanged) when none is.
template <class E, class Values = std::initializer_list<E>>
bool parse_by_name(std::string_view text, const Values& values, E* out) {
  for (const E& v : values)
    if (text == to_string(v)) {  // found by argument-dependent lookup in E's namespace
      *out = v;
      return true;
    }
  return false;
}

// "a, b or c": the names of `values` for a message ("expected a, b or c").
template <class Values>
std::string names_or(const Values& values) {
  std::string out;
  std::size_t k = 0;
  const auto n = static_cast<std::size_t>(std::end(values) - std::begin(values));
  for (const auto& v : values) {
    if (k > 0) out += k + 1 == n ? " or " : ", ";
    out += std::string(to_string(v));
    ++k;
  }
  return out;
}

}  // namespace odotune::core
