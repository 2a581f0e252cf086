// The report folder of `odotune diagnose TRACK --report DIR`: the diagnosis
// figures (odotune/results/diagnosis_figures.h) and one self-contained page
// DIR/index.html (figures inlined as SVG, no scripts, no links). Builds and
// writes files only; the command prints.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <odotune/results/diagnosis_figures.h>

namespace odotune::results {

// Creates DIR if needed and writes into it the figures of
// diagnosis_figures() and index.html: title (the track), `summary_lines` as a
// list, each figure inlined with a caption saying what it shows, and
// `json_text` (the diagnosis result) HTML-escaped in a <pre> block.
//
// All or nothing as far as practical: the figures are drawn into a private
// staging folder inside DIR first; only when every figure and the page are
// ready are the figures renamed into DIR (a stale residual_condition.* of an
// earlier run is removed when this one has none) and index.html written
// atomically. On any failure DIR keeps what it had before (no index.html,
// no figures of this call) and the staging folder is removed.
//
// Throws std::invalid_argument on malformed `data` (see diagnosis_figures())
// and std::runtime_error with one line when DIR cannot be created or
// written, or gnuplot is missing or fails.
void write_diagnosis_report(const std::filesystem::path& dir, const DiagnosisFigureData& data,
                            const std::vector<std::string>& summary_lines, const std::string& json_text);

}  // namespace odotune::results
