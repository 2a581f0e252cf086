// What the --report figures of `odotune diagnose` show, taken from a
// Diagnosis (odotune/results/diagnosis_figures.h takes plain data only):
//  1. residual vs time: |position error| of the windowed replay, nominal and
//     chosen model, per reference sample; the segments located on the
//     nominal residuals (else those of the first finding) shaded; window
//     starts marked.
//  2. residual vs the condition it grows with most (locate.h's strongest
//     rank correlation): the growth z-score of locate.h (growth of the
//     residual over ~1 s divided by its noise sigma), nominal and chosen model.
//  3. map: the reference path, the samples whose growth exceeds the noise,
//     the located regions (and the findings' regions, e.g. a slip zone box).
//  4. overlay: reference, nominal and chosen model dead-reckoned over the
//     whole track from one anchor (window 0: drift shows as it builds up).
#pragma once

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/diagnosis.h>
#include <odotune/results/diagnosis_figures.h>

namespace odotune::jobs {

results::DiagnosisFigureData diagnosis_figure_data(const diagnose::DiagInput& in, const diagnose::Diagnosis& d,
                                                   const std::string& finding_text);

}  // namespace odotune::jobs
