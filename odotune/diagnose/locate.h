// Step 6 of the diagnosis (docs/diagnosis-design.md): where and under which
// conditions the nominal model's residuals exceed what noise explains.
//
// Input: the residual series of a window replay (window_replay.h), one row
// per reference sample: the error predicted − reference (position, and
// heading when the reference has it), the window the row belongs to (the
// dead reckoning is re-anchored at each window's start), and the robot's
// state there (from the reference).
//
// Growth, not level. After re-anchoring, the residual LEVEL says mostly how
// long ago the window started; where the mismatch happens shows in its
// GROWTH. For each row i the growth rate is the centred difference
//     d_i = (e_b − e_a) / (t_b − t_a),
// a = first row of the same window with t ≥ t_i − span/2, b = last with
// t ≤ t_i + span/2, span = max(growth_span_s, (min_span_samples − 1) × the
// median sampling period) (so 1 Hz fixes get a 2 s span). Near a window's
// edges the interval is shifted to lie inside the window; rows whose
// interval is still shorter than span/2 get no growth. Each d_i is scaled
// by (t_b − t_a) / (median of t_b − t_a) so that all rows share one noise
// level (white-noise law), otherwise short intervals would over-flag.
//
// Noise level of the growth, robust (MAD) and model-free: σ_d = 1.4826 ×
// MAD of the differences d_i − d_j / √2, j the first row more than one span
// after i in the same window (disjoint spans, so independent noise; x and y
// pooled). Differencing removes any growth that is
// steady over a span, so effects that act most of the time do not inflate
// σ_d, and the same formula is right for white reference noise and for the
// odometry's random walk. Floors: √2·sigma_m/span (white reference noise of
// the given σ per axis) and min_sigma_m/span; likewise for heading.
//
// Per row: z_i = max(|d_xy,i| / σ_d_xy, |d_θ,i| / σ_d_θ) (NaN where no
// growth); an exceedance is z_i > threshold_sigma.
//   (a) segments: runs of exceedances, merged across gaps < merge_gap_s,
//       kept when they last ≥ min_segment_s and hold ≥ min_segment_samples
//       exceedances. Isolated noise exceedances never form a segment; a row
//       is FLAGGED when it is an exceedance inside a kept segment, and (b)
//       and (c) use the flagged rows only, so pure noise yields no region
//       and no phrase;
//   (b) regions: a grid of cell_m cells over the visited area; a cell is
//       flagged when it has ≥ min_cell_samples rows and a flagged fraction
//       ≥ max(cell_min_flagged_fraction, cell_enrichment × the overall
//       fraction); 8-connected flagged cells merge into boxes (cell edges).
//       No regions when flagged cells cover more than region_max_cover of the
//       visited cells (the mismatch is not a matter of place);
//   (c) conditions: Spearman rank correlation of z with v, |w|, |v·w|, |a|,
//       x, y and time since start, ranked by |ρ|. For each, the threshold
//       (a 5 %…95 % quantile of the condition, beyond it = above for ρ > 0,
//       below otherwise) maximising Youden's J = (flagged rows beyond /
//       flagged rows) − (unflagged rows beyond / unflagged rows). The phrase
//       names the strongest condition (|ρ| ≥ min_rank_correlation, J ≥
//       min_youden_j) with its threshold, plus a second condition when,
//       among the rows beyond the first threshold, its own best J is ≥
//       min_youden_j (|w| and |v·w| never pair: both are turning), e.g. "turns faster than 0.5 rad/s at speeds above
//       0.4 m/s" (a turn-rate part is always written first). The parts are
//       also returned as data. Empty when nothing is flagged.
//
// No I/O. SI units.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace odotune::diagnose {

// One row per reference sample. All arrays have the same length except
// e_theta_rad, which is empty without a reference heading.
struct ResidualSeries {
  std::vector<double> t_s;          // non-decreasing; strictly increasing within a window
  std::vector<double> ex_m, ey_m;   // predicted − reference position [m]
  std::vector<double> e_theta_rad;  // predicted − reference heading [rad], or empty
  std::vector<int> window;          // replay window id, non-decreasing
  // Robot state at the row (from the reference).
  std::vector<double> x_m, y_m;    // position [m]
  std::vector<double> v_mps;       // speed [m/s] (signed)
  std::vector<double> w_radps;     // yaw rate [rad/s]
  std::vector<double> accel_mps2;  // linear acceleration [m/s^2]
  std::vector<double> t_since_start_s;

  // Lengths, finiteness and ordering; `why` names the first broken rule.
  bool IsValid(std::string* why) const;
};

struct LocateOptions {
  double growth_span_s = 1.0;    // span of the centred growth rate [s]
  int min_span_samples = 3;      // a span covers at least this many rows
  double threshold_sigma = 4.0;  // flag when z > this
  double min_sigma_m = 1e-4;     // floor of the position noise [m]
  double min_sigma_rad = 1e-5;   // floor of the heading noise [rad]
  double merge_gap_s = 2.0;      // merge segments closer than this [s]
  double min_segment_s = 1.0;    // drop shorter segments [s]
  int min_segment_samples = 3;   // drop segments with fewer flagged rows
  double cell_m = 0.5;           // grid cell edge [m] (enlarged if the area needs > max_cells_per_axis)
  int max_cells_per_axis = 200;
  int min_cell_samples = 3;
  double cell_min_flagged_fraction = 0.3;
  double cell_enrichment = 3.0;
  double region_max_cover = 0.5;      // fraction of visited cells
  double min_rank_correlation = 0.1;  // |ρ| needed for the phrase
  double min_youden_j = 0.3;          // J needed for a phrase part

  bool IsValid(std::string* why) const;
};

enum class Condition { speed, turn_rate, turn_speed, acceleration, x, y, time };
inline constexpr int kNumConditions = 7;
// "v", "|w|", "|v*w|", "|a|", "x", "y", "t".
std::string_view condition_name(Condition c);
// The condition's value at row i of the series (|w|, |v*w|, |a| as magnitudes).
double condition_value(const ResidualSeries& s, Condition c, std::size_t i);

struct TimeSegment {
  double t0_s = 0.0, t1_s = 0.0;  // first and last flagged row
  double peak_z = 0.0;
  int flagged = 0;  // flagged rows inside
};

struct MapRegion {
  double x0_m = 0.0, x1_m = 0.0, y0_m = 0.0, y1_m = 0.0;  // box (cell edges)
  int cells = 0;
  int samples = 0, flagged = 0;  // rows inside the flagged cells
};

struct ConditionRank {
  Condition condition = Condition::speed;
  double rho = 0.0;   // Spearman ρ of z with the condition's value
  bool above = true;  // flagged rows lie above (ρ > 0) or below the threshold
  double threshold = std::numeric_limits<double>::quiet_NaN();  // condition units
  double youden_j = 0.0;                                        // of the threshold (0 when nothing is flagged)
};

// One part of the phrase: rows with the condition above (below) threshold.
struct ConditionPart {
  Condition condition = Condition::speed;
  bool above = true;
  double threshold = 0.0;
};

struct Location {
  double span_s = 0.0;
  double sigma_growth_mps = 0.0;      // noise σ of the position growth rate [m/s]
  double sigma_growth_radps = 0.0;    // of the heading growth rate [rad/s] (0 without heading)
  std::vector<double> z;              // per row; NaN where no growth is defined
  int exceedances = 0;                // rows with z > threshold_sigma
  std::vector<std::uint8_t> flagged;  // per row, 1 = an exceedance inside a kept segment
  int flagged_count = 0;
  std::vector<TimeSegment> segments;        // in time order
  std::vector<MapRegion> regions;           // most flagged rows first
  std::vector<ConditionRank> conditions;    // by |ρ|, strongest first
  std::vector<ConditionPart> phrase_parts;  // 0–2, in the phrase's order
  std::string phrase;                       // "" when nothing stands out
};

// Throws std::invalid_argument (one line) for invalid options or series, or
// a negative / non-finite sigma_m (the reference's position noise per axis,
// 0 when unknown: then only the robust estimate and the floors count).
Location locate(const ResidualSeries& series, double sigma_m, const LocateOptions& options = {});

}  // namespace odotune::diagnose
