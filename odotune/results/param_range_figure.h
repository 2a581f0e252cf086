// How well the tuning data pin each tuned parameter, as a figure: per
// parameter, each series' (e.g. each seed's) range and tuned value on a
// log10 axis, against the reference value the factors multiply (the
// parameter file's own value, factor 1). Rendered with gnuplot like the
// report's other figures (odotune/results/figures.h): STEM.png + STEM.svg or
// nothing, texts verbatim.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <odotune/results/run_record.h>

namespace odotune::results {

struct ParamRangeSeries {
  std::string name;                // legend entry, e.g. "seed 1"
  std::vector<double> values;      // per parameter: the tuned value
  std::vector<ParamRange> ranges;  // per parameter: its range
};

// One row per parameter (`params`, top to bottom); in each row one thin
// horizontal bar per series, side by side, from lo to hi in the series'
// colour (pale with a dashed outline and labelled "not determined" when
// determined is false),
// the tuned value as a black dot on it, and a dashed vertical line at
// `reference` (legend `reference_label`), on a log10 x axis labelled `x_label` that holds every
// positive finite bound and value and the reference with a small margin.
// A bound that is not positive and finite is drawn to the axis' edge; a
// value that is not is left out. Throws std::invalid_argument when `params`
// or `series` is empty, a series' values or ranges are not one per
// parameter, or no value, bound or reference is positive and finite;
// otherwise as odotune/results/figures.h.
void param_ranges_figure(const std::filesystem::path& stem, const std::string& title,
                         const std::string& x_label, const std::vector<std::string>& params,
                         const std::vector<ParamRangeSeries>& series, double reference,
                         const std::string& reference_label);

}  // namespace odotune::results
