// `odotune fixes`: a track file given synthetic absolute position fixes made
// from its ground truth (odotune/sim/synthetic_fixes.h), written to another file.
// The command reads the flags and prints.
#pragma once

#include <string>

#include <odotune/sim/synthetic_fixes.h>

namespace odotune::jobs {

struct FixesRequest {
  std::string track;   // input track file
  std::string output;  // track file to write (existing aps_x/aps_y replaced)
  sim::SyntheticFixOptions options;
};

// Returns how the fixes were made (the written track's fixes.synthetic
// metadata). Throws core::Failure (one line) on invalid options, an
// unreadable track or one without ground truth, or a failed write.
std::string run_fixes(const FixesRequest& request);

}  // namespace odotune::jobs
