// kNaN, the quiet NaN that marks a value not measured or not defined (an
// empty sample's statistic, a check that did not run), and kInf, a cost or
// bound not yet met; one definition for the files of a module that compile
// together in a unity batch.
#pragma once

#include <limits>

namespace odotune::core {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace odotune::core
