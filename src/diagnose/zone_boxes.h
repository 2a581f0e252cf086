// Candidate slip-zone boxes (physics-effects.md, slip_zone) from where a
// model's dead-reckoning residual GROWS on the map, for the model selection
// (select.h). A simple stand-in for the regions of locate.h, whose boxes the
// selection also accepts (SelectOptions::zone_boxes).
#pragma once

#include <vector>

#include "diagnose/diag_input.h"
#include "diagnose/window_replay.h"

namespace odotune::diagnose {

// An axis-aligned box of the world frame [m] (x0 < x1, y0 < y1).
struct ZoneBox {
  double x0_m = 0.0, x1_m = 0.0, y0_m = 0.0, y1_m = 0.0;
  double score = 0.0;  // zone_candidates' score (unused in boxes given to the selection)
};

// Candidate boxes from the predictions pred_* of a model (per reference
// sample of `in`; NaN allowed outside the scored samples of `windows`).
//
// Growth. For each pair of consecutive scored samples p -> g of a window,
// with residual e = predicted - reference, the growth along the direction of
// travel t (of the PREDICTED step p -> g: smooth, whereas the reference's
// noise would bias a; a = 0 for steps shorter than ref_sigma_m, whose
// direction wanders when turning on the spot, so that their noise would not
// telescope), a = (e_g - e_p).t [m], and of the heading residual,
// h [rad] (with a reference heading), belong to the grid cell of
// cell_m holding the midpoint (cells enlarged to at most 400 per axis). The
// background growth per metre travelled (median over cells with more than a
// cell's length of travel) is subtracted: what is left is growth bound to a
// place. A slip zone makes the wheels overshoot the ground, so a > 0.
//
// Score of a box: max(A, 0)^2 / (2 sigma_m^2 P) + H^2 / (2 sigma_rad^2 P),
// A, H the summed excess growth of the increments inside, P the number of
// passes (runs of consecutive increments inside); within a pass the sum
// telescopes to the residual difference between exit and entry, so the
// reference noise (DiagInput::ref_sigma_*) adds about 2 sigma^2 per pass:
// the score is a chi-square-like signal-to-noise ratio.
//
// Boxes. Seeds are single cells in order of score (at least min_score/4,
// at most 10*max_boxes tried, none inside an earlier box); a seed grows by
// the one row or column of cells (of four) that raises sqrt(score) most, while
// it raises it by at least 1 (a cell with no slip in it moves the sum by
// reference noise only). Boxes (cell edges) scoring at least min_score are
// returned, best seed first, at most max_boxes. Throws std::invalid_argument
// when pred_x_m or pred_y_m do not have one value per reference sample.
std::vector<ZoneBox> zone_candidates(const DiagInput& in, const std::vector<Window>& windows,
                                     const std::vector<double>& pred_x_m,
                                     const std::vector<double>& pred_y_m,
                                     const std::vector<double>& pred_theta_rad, double cell_m,
                                     int max_boxes, double min_score);

}  // namespace odotune::diagnose
