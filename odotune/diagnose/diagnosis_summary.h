// The human summary `odotune diagnose` prints on stdout. Its first line is one
// sentence: what the nominal model left out, its fitted
// size with uncertainty, and the held-out improvement; or that nothing beyond
// sensor noise was found; or where an unexplained mismatch appears.
// Later lines: one per finding (where, conditions, share explained, held-out
// before → after, confounded rivals), then the baseline and final errors.
#pragma once

#include <string>
#include <vector>

#include <odotune/diagnose/diagnosis.h>
#include <odotune/diagnose/recordings.h>

namespace odotune::diagnose {

std::vector<std::string> diagnosis_summary(const Diagnosis& d);

// Several recordings: the pooled summary, then one line per recording
// (role, nominal -> pooled-model error) and what holds across recordings.
std::vector<std::string> pooled_summary(const PooledDiagnosis& p);

// "k = 0.0212 ± 0.0018" / "scale_l = 0.99400 ± 0.00021, scale_r = ..." with
// the units of physics-effects.md; significant digits follow the uncertainty.
std::string finding_size(const Finding& f);

}  // namespace odotune::diagnose
