// Slip-zone boxes (physics-effects.md, slip_zone) for the model selection
// (select.h): candidate boxes from where a model's dead-reckoning residual
// GROWS on the map (a simple stand-in for the regions of locate.h, whose
// boxes the selection also accepts, SelectOptions::zone_boxes), and the
// choice and refinement of the box by fit cost (choose_zone_box).
#pragma once

#include <vector>

#include <odotune/diagnose/cross_validate.h>
#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/effect_model.h>
#include <odotune/diagnose/window_replay.h>

namespace odotune::diagnose {

// An axis-aligned box of the world frame [m] (x0 < x1, y0 < y1).
struct ZoneBox {
  double x0_m = 0.0, x1_m = 0.0, y0_m = 0.0, y1_m = 0.0;
  double score = 0.0;   // zone_candidates' score (unused in boxes given to the selection)
  double cell_m = 0.0;  // the grid's cell it was found on (0: not from a grid)
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
// returned, best seed first, at most max_boxes.
//
// Scales. All this on three grids, cells of cell_m, 2 cell_m and 4 cell_m,
// on the coarsest by scoring every box of 1-4 cells per side instead of
// growing seeds, and the max_boxes best boxes of the three kept (a box whose
// centre lies in a better one dropped): with sparse fixes (1 Hz, 0.2-0.5 m apart, 20-50 mm
// noise) a single fine cell holds one noisy increment per pass, too little
// for a seed to stand out or to grow, while a patch of a few metres shows on
// the coarser grids (a 2.4 m x 1.8 m patch,
// s = 0.07 crossed three times, scores 54 as a whole, but no seed of the
// 0.25 m grid grew into a box). Throws std::invalid_argument
// when pred_x_m or pred_y_m do not have one value per reference sample.
std::vector<ZoneBox> zone_candidates(const DiagInput& in, const std::vector<Window>& windows,
                                     const std::vector<double>& pred_x_m, const std::vector<double>& pred_y_m,
                                     const std::vector<double>& pred_theta_rad, double cell_m, int max_boxes,
                                     double min_score);

struct ZoneSearchOptions {
  double cell_m = 0.25;              // zone_candidates' cell, and the refinement's unit [m]
  int max_boxes = 3;                 // boxes from zone_candidates
  double min_score = 16.0;           // their score threshold
  std::vector<ZoneBox> extra_boxes;  // more candidates (e.g. from locate.h)
  int max_iterations = 20;           // of each fit
  double max_share = 0.5;            // a box may hold at most this share of the scored reference samples
};

// The structure s plus slip_zone with the best box, or an empty set when
// there is no candidate. Candidates: zone_candidates on cur_full's
// predictions (cv.fit_all of s) plus extra_boxes, but none (and no refined
// box) that holds more than max_share of the scored reference samples: a
// slip zone is a place, and a box over most of the path fits a radius error
// as well as radius_error does (a pooled fit of three recordings with a 1 %
// radius error chose a coarse box over half the map, slips 0.01); each is fitted (s_l, s_r
// beside s held at cur_full.fitted) on the windows of cv whose reference or
// predicted path comes within 1 m of it, and the lowest cost (the fit's final
// cost minus those windows' settled costs without slip: what the slips
// remove, CrossValidator::settled_costs) wins. Unless its slips both stay
// below 0.01 and its cost is above -11.23 (a box from noise; a
// box larger than the patch dilutes the slip), its edges are then refined by coordinate search on the fit cost
// in steps of half the box's own grid cell (ZoneBox::cell_m, at least
// cell_m), halved down to cell_m/4 (up to 4 rounds each; a round moves
// each edge out and in, in order, keeping each move that lowers the cost;
// the remaining moves are fitted speculatively in parallel from the current
// box, and those after a kept move fitted again, so the result is that of
// one move at a time for any number of threads), and the edges
// the data does not determine are set by the isotropic-patch convention of
// select.h (moved out to the square centred on the inside samples whose
// side is the box's larger extent, or half or a quarter of the way, where
// the fit cost rises by less than 1.92 = half the 95 % point of chi-square
// with 1 degree of freedom). The returned set holds no-op slips (fitted
// values are the caller's business).
EffectSet choose_zone_box(CrossValidator& cv, const EffectSet& s, const SetEval& cur_full,
                          const ZoneSearchOptions& options);

}  // namespace odotune::diagnose
