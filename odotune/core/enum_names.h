// Parsing an enum from the names its to_string gives (Ceres' pairing of
// XToString and StringToX): one loop for every enum instead of one per enum.
#pragma once

#include <initializer_list>
#include <string_view>

namespace odotune::core {

// Sets *out to the value of `values` whose to_string(value) is `text`;
// false (and *out unchanged) when none is.
template <class E>
bool parse_by_name(std::string_view text, std::initializer_list<E> values, E* out) {
  for (E v : values)
    if (text == to_string(v)) {  // found by argument-dependent lookup in E's namespace
      *out = v;
      return true;
    }
  return false;
}

}  // namespace odotune::core
