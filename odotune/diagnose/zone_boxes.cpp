#include <odotune/diagnose/zone_boxes.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include <odotune/core/non_finite.h>
#include <odotune/core/robust_stats.h>

namespace odotune::diagnose {

namespace {

using core::kInf;
using core::kNaN;
// A found box whose fitted slips both stay below this is not refined (a box
// from noise is not worth the fits) unless its fit cost fell by kRefineCost
// or more: a box larger than the patch dilutes the slip (slips 0.013/0.014
// in a 2.7 m patch fitted 0.004/0.008 in the 4 m box of the coarse grid,
// which was then never refined; docs/diagnosis-design.md, "Cases behind the
// rules").
constexpr double kMinZoneSlip = 0.01;
// Half the 99.9 % point of a chi-square with six degrees of freedom (the
// box's four edges and two slips): 22.46 / 2.
constexpr double kRefineCost = 11.23;
// A slip-zone edge whose outward move raises the fit cost (1/2 chi-square)
// by less than this is not determined by the data: half the 95 % point of a
// chi-square with one degree of freedom (3.84).
constexpr double kFlatCost = 1.92;
// Windows whose reference or predicted path comes this close to a box [m]
// take part in its fit: a refinement move shifts an edge by at most a cell,
// and the prediction strays from the reference by its residual.
constexpr double kZoneReachM = 1.0;

// Windows of cv with a scored sample (reference or cur's prediction) within
// reach_m of box b.
std::vector<int> windows_near(const CrossValidator& cv, const SetEval& cur, const ZoneBox& b, double reach_m) {
  const DiagInput& in = cv.input();
  const auto near = [&](double x, double y) {
    return x >= b.x0_m - reach_m && x <= b.x1_m + reach_m && y >= b.y0_m - reach_m && y <= b.y1_m + reach_m;
  };
  std::vector<int> out;
  for (const Window& w : cv.windows())
    for (std::size_t g = w.ref_begin; g < w.ref_end; ++g)
      if (near(in.ref_x_m[g], in.ref_y_m[g]) || near(cur.pred.x_m[g], cur.pred.y_m[g])) {
        out.push_back(w.index);
        break;
      }
  return out;
}

}  // namespace

namespace {

// The max_boxes best of `boxes` (by score, stable), none whose centre lies
// in a better one kept.
std::vector<ZoneBox> best_apart(std::vector<ZoneBox> boxes, int max_boxes) {
  std::stable_sort(boxes.begin(), boxes.end(),
                   [](const ZoneBox& a, const ZoneBox& b) { return a.score > b.score; });
  std::vector<ZoneBox> out;
  for (const ZoneBox& b : boxes) {
    if (static_cast<int>(out.size()) >= max_boxes) break;
    const double cx = 0.5 * (b.x0_m + b.x1_m), cy = 0.5 * (b.y0_m + b.y1_m);
    if (std::none_of(out.begin(), out.end(), [&](const ZoneBox& k) {
          return cx >= k.x0_m && cx <= k.x1_m && cy >= k.y0_m && cy <= k.y1_m;
        }))
      out.push_back(b);
  }
  return out;
}

// One step of a window's reference path, for the zone grid: its midpoint,
// the growth of the along-track (a) and heading (h) residual over it, the
// predicted travel `len`, and its grid cell.
struct Inc {
  double x, y, a, h, len;
  bool cont;  // continues the previous increment's run of samples
  int cx = 0, cy = 0;
};

// A box of grid cells.
struct Rect {
  int x0, x1, y0, y1;  // inclusive cell ranges
};

// The increments of every window's scored samples (those with finite
// predictions), and their bounding box.
struct Increments {
  std::vector<Inc> inc;
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
};
Increments increments(const DiagInput& in, const std::vector<Window>& windows,
                      const std::vector<double>& pred_x_m, const std::vector<double>& pred_y_m,
                      const std::vector<double>& pred_theta_rad, bool heading) {
  Increments r;
  std::vector<Inc>& inc = r.inc;
  std::size_t last_g = 0;  // sample the previous increment ended at
  for (const Window& w : windows)
    for (std::size_t g = w.ref_begin + 1; g < w.ref_end; ++g) {
      const std::size_t p = g - 1;
      if (!(std::isfinite(pred_x_m[g]) && std::isfinite(pred_x_m[p]) && std::isfinite(pred_y_m[g]) &&
            std::isfinite(pred_y_m[p])))
        continue;
      // Direction and length of travel from the prediction: dead reckoning
      // is smooth, the reference's noise would bias a (long noisy steps point
      // along their own noise).
      const double ux = pred_x_m[g] - pred_x_m[p], uy = pred_y_m[g] - pred_y_m[p];
      const double len = std::hypot(ux, uy);
      const double gx = (pred_x_m[g] - in.ref_x_m[g]) - (pred_x_m[p] - in.ref_x_m[p]);
      const double gy = (pred_y_m[g] - in.ref_y_m[g]) - (pred_y_m[p] - in.ref_y_m[p]);
      // Steps shorter than the reference noise (turning on the spot) have no
      // steady direction: summed over a pass their noise would not telescope.
      const bool moving = len >= in.ref_sigma_m;
      Inc k{0.5 * (in.ref_x_m[g] + in.ref_x_m[p]),
            0.5 * (in.ref_y_m[g] + in.ref_y_m[p]),
            moving ? (gx * ux + gy * uy) / len : 0.0,
            0.0,
            moving ? len : 0.0,
            !inc.empty() && last_g == p};
      if (heading && std::isfinite(pred_theta_rad[g]) && std::isfinite(pred_theta_rad[p]))
        k.h = (pred_theta_rad[g] - in.ref_theta_rad[g]) - (pred_theta_rad[p] - in.ref_theta_rad[p]);
      r.xmin = std::min(r.xmin, k.x);
      r.xmax = std::max(r.xmax, k.x);
      r.ymin = std::min(r.ymin, k.y);
      r.ymax = std::max(r.ymax, k.y);
      inc.push_back(k);
      last_g = g;
    }
  return r;
}

// The increments on a grid of nx × ny cells of `cell` metres from (xmin,
// ymin), the travel and growth summed per cell, and the background growth
// per metre; scores boxes of cells.
struct ZoneGrid {
  std::vector<Inc> inc;
  double xmin = 0.0, ymin = 0.0, cell = 0.0;
  int nx = 0, ny = 0;
  std::vector<double> ca, ch, cl;  // per cell: along-track growth, heading growth, travel
  double bg_a = 0.0, bg_h = 0.0;
  bool heading = false;
  double sm2 = 1.0, sh2 = 1.0;

  // The growth inside r beyond the background, squared over its noise
  // (2 × passes reference variances), along track plus heading.
  double score(const Rect& r) const {
    double a = 0.0, h = 0.0;
    int passes = 0;
    bool prev_in = false;
    for (const Inc& k : inc) {
      const bool in_r = k.cx >= r.x0 && k.cx <= r.x1 && k.cy >= r.y0 && k.cy <= r.y1;
      if (in_r) {
        a += k.a - bg_a * k.len;
        h += k.h - bg_h * k.len;
        if (!(prev_in && k.cont)) ++passes;
      }
      prev_in = in_r;
    }
    if (passes == 0) return 0.0;
    const double p2 = 2.0 * passes;
    return std::max(a, 0.0) * std::max(a, 0.0) / (p2 * sm2) + (heading ? h * h / (p2 * sh2) : 0.0);
  }
  ZoneBox box(const Rect& r, double v) const {
    return {
        xmin + r.x0 * cell, xmin + (r.x1 + 1) * cell, ymin + r.y0 * cell, ymin + (r.y1 + 1) * cell, v, cell};
  }
};

// The grid over `incs` (at least cell_m, at most 400 cells per side), each
// increment's cell, the per-cell sums and the background growth per metre.
ZoneGrid zone_grid(Increments incs, double cell_m) {
  ZoneGrid z;
  z.inc = std::move(incs.inc);
  const double xmin = incs.xmin, xmax = incs.xmax, ymin = incs.ymin, ymax = incs.ymax;
  z.xmin = xmin;
  z.ymin = ymin;
  const double cell = std::max({cell_m, (xmax - xmin) / 400.0, (ymax - ymin) / 400.0});
  z.cell = cell;
  const int nx = static_cast<int>((xmax - xmin) / cell) + 1, ny = static_cast<int>((ymax - ymin) / cell) + 1;
  z.nx = nx;
  z.ny = ny;
  for (Inc& k : z.inc) {
    k.cx = std::min(nx - 1, static_cast<int>((k.x - xmin) / cell));
    k.cy = std::min(ny - 1, static_cast<int>((k.y - ymin) / cell));
  }
  // Background growth per metre: median over cells with some travel.
  std::vector<double> ca(static_cast<std::size_t>(nx * ny), 0.0), ch(ca), cl(ca);
  for (const Inc& k : z.inc) {
    const auto i = static_cast<std::size_t>(k.cy) * static_cast<std::size_t>(nx) +
                   static_cast<std::size_t>(k.cx);
    ca[i] += k.a;
    ch[i] += k.h;
    cl[i] += k.len;
  }
  std::vector<double> ra, rh;
  for (std::size_t i = 0; i < cl.size(); ++i)
    if (cl[i] > cell) ra.push_back(ca[i] / cl[i]), rh.push_back(ch[i] / cl[i]);
  // The background: the median cell (0 without cells).
  z.bg_a = ra.empty() ? 0.0 : core::median(std::move(ra), core::MedianRule::upper_middle);
  z.bg_h = rh.empty() ? 0.0 : core::median(std::move(rh), core::MedianRule::upper_middle);
  z.ca = std::move(ca);
  z.ch = std::move(ch);
  z.cl = std::move(cl);
  return z;
}

// Every box of 1..exhaustive_cells cells per side that holds some travel,
// best first, none whose centre lies in a better one.
std::vector<ZoneBox> exhaustive_boxes(const ZoneGrid& z, int exhaustive_cells, int max_boxes,
                                      double min_score) {
  const int nx = z.nx, ny = z.ny;
  // Cells with travel, as 2D prefix counts: a box without any is skipped
  // unscored (a large drive's area is mostly empty).
  std::vector<int> pre(static_cast<std::size_t>((nx + 1) * (ny + 1)), 0);
  const auto P = [&](int x, int y) -> int& {
    return pre[static_cast<std::size_t>(y) * static_cast<std::size_t>(nx + 1) + static_cast<std::size_t>(x)];
  };
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x)
      P(x + 1, y + 1) =
          P(x, y + 1) + P(x + 1, y) - P(x, y) +
          (z.cl[static_cast<std::size_t>(y) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(x)] >
           0.0);
  std::vector<ZoneBox> all;
  for (int y0 = 0; y0 < ny; ++y0)
    for (int x0 = 0; x0 < nx; ++x0)
      for (int h = 1; h <= exhaustive_cells && y0 + h <= ny; ++h)
        for (int w = 1; w <= exhaustive_cells && x0 + w <= nx; ++w) {
          if (P(x0 + w, y0 + h) - P(x0, y0 + h) - P(x0 + w, y0) + P(x0, y0) == 0) continue;
          const Rect r{x0, x0 + w - 1, y0, y0 + h - 1};
          const double v = z.score(r);
          if (v >= min_score) all.push_back(z.box(r, v));
        }
  return best_apart(std::move(all), max_boxes);
}

// Grows r, of score sc, one side at a time by the best of the four one-cell
// moves while sqrt(score) rises by at least one noise unit (a cell without
// slip moves the sum by reference noise alone).
void grow_rect(const ZoneGrid& z, Rect& r, double& sc) {
  for (;;) {
    const Rect tries[4] = {{r.x0 - 1, r.x1, r.y0, r.y1},
                           {r.x0, r.x1 + 1, r.y0, r.y1},
                           {r.x0, r.x1, r.y0 - 1, r.y1},
                           {r.x0, r.x1, r.y0, r.y1 + 1}};
    double bs = sc;
    int bi = -1;
    for (int t = 0; t < 4; ++t) {
      const Rect& q = tries[t];
      if (q.x0 < 0 || q.y0 < 0 || q.x1 >= z.nx || q.y1 >= z.ny) continue;
      const double v = z.score(q);
      if (v > bs) {
        bs = v;
        bi = t;
      }
    }
    if (bi < 0 || std::sqrt(bs) < std::sqrt(sc) + 1.0) break;
    r = tries[bi];
    sc = bs;
  }
}

// Boxes grown from the best-scoring cells (at most 10 × max_boxes seeds,
// none inside a box already grown).
std::vector<ZoneBox> grown_boxes(const ZoneGrid& z, int max_boxes, double min_score) {
  const int nx = z.nx, ny = z.ny;
  std::vector<std::pair<double, int>> seeds;
  for (int i = 0; i < nx * ny; ++i)
    if (z.cl[static_cast<std::size_t>(i)] > 0.0 || z.ch[static_cast<std::size_t>(i)] != 0.0)
      seeds.push_back({z.score({i % nx, i % nx, i / nx, i / nx}), i});
  std::sort(seeds.begin(), seeds.end(), [](const auto& a, const auto& b) {
    return a.first > b.first || (a.first == b.first && a.second < b.second);
  });
  std::vector<Rect> found;
  std::vector<ZoneBox> out;
  for (std::size_t si = 0; si < seeds.size() && static_cast<int>(out.size()) < max_boxes &&
                           si < 10 * static_cast<std::size_t>(max_boxes);
       ++si) {
    const int cx = seeds[si].second % nx, cy = seeds[si].second / nx;
    const bool covered = std::any_of(found.begin(), found.end(), [&](const Rect& r) {
      return cx >= r.x0 && cx <= r.x1 && cy >= r.y0 && cy <= r.y1;
    });
    if (covered || seeds[si].first < 0.25 * min_score) continue;
    Rect r{cx, cx, cy, cy};
    double sc = seeds[si].first;
    grow_rect(z, r, sc);
    found.push_back(r);
    if (sc < min_score) continue;
    out.push_back(z.box(r, sc));
  }
  return out;
}

// zone_candidates on one grid of cell_m (header comment).
std::vector<ZoneBox> zone_candidates_at(const DiagInput& in, const std::vector<Window>& windows,
                                        const std::vector<double>& pred_x_m,
                                        const std::vector<double>& pred_y_m,
                                        const std::vector<double>& pred_theta_rad, double cell_m, int max_boxes,
                                        double min_score, int exhaustive_cells) {
  const bool heading = in.has_ref_heading() && pred_theta_rad.size() == in.ref_t_s.size();
  const double sm2 = in.ref_sigma_m * in.ref_sigma_m;
  const double sh2 = heading ? in.ref_sigma_rad * in.ref_sigma_rad : 1.0;
  Increments incs = increments(in, windows, pred_x_m, pred_y_m, pred_theta_rad, heading);
  if (incs.inc.empty() || max_boxes <= 0) return {};
  ZoneGrid z = zone_grid(std::move(incs), cell_m);
  z.heading = heading;
  z.sm2 = sm2;
  z.sh2 = sh2;
  if (exhaustive_cells > 0) return exhaustive_boxes(z, exhaustive_cells, max_boxes, min_score);
  return grown_boxes(z, max_boxes, min_score);
}

}  // namespace

std::vector<ZoneBox> zone_candidates(const DiagInput& in, const std::vector<Window>& windows,
                                     const std::vector<double>& pred_x_m, const std::vector<double>& pred_y_m,
                                     const std::vector<double>& pred_theta_rad, double cell_m, int max_boxes,
                                     double min_score) {
  if (pred_x_m.size() != in.ref_t_s.size() || pred_y_m.size() != in.ref_t_s.size())
    throw std::invalid_argument(fmt::format("zone_candidates: {} and {} predictions for {} reference "
                                            "samples",
                                            pred_x_m.size(), pred_y_m.size(), in.ref_t_s.size()));
  // Three grids (header comment, "Scales"): the best boxes of all, a box
  // whose centre lies in a better one dropped.
  std::vector<ZoneBox> all;
  for (double scale : {1.0, 2.0, 4.0}) {
    const std::vector<ZoneBox> b = zone_candidates_at(in, windows, pred_x_m, pred_y_m, pred_theta_rad,
                                                      scale * cell_m, max_boxes, min_score,
                                                      scale > 2.0 ? 4 : 0);
    all.insert(all.end(), b.begin(), b.end());
  }
  return best_apart(std::move(all), max_boxes);
}

namespace {

// Centre of the scored reference samples inside box b along x (axis 0) or
// y (axis 1); NaN when none is inside.
double inside_centre(const DiagInput& in, const std::vector<Window>& windows, const ZoneBox& b, int axis) {
  double lo = kInf, hi = -kInf;
  for (const Window& w : windows)
    for (std::size_t g = w.ref_begin; g < w.ref_end; ++g)
      if (in.ref_x_m[g] >= b.x0_m && in.ref_x_m[g] <= b.x1_m && in.ref_y_m[g] >= b.y0_m &&
          in.ref_y_m[g] <= b.y1_m) {
        const double u = axis == 0 ? in.ref_x_m[g] : in.ref_y_m[g];
        lo = std::min(lo, u);
        hi = std::max(hi, u);
      }
  return lo <= hi ? 0.5 * (lo + hi) : kNaN;
}

// Share of the scored reference samples of `windows` inside box b.
double inside_share(const DiagInput& in, const std::vector<Window>& windows, const ZoneBox& b) {
  std::size_t inside = 0, all = 0;
  for (const Window& w : windows)
    for (std::size_t g = w.ref_begin; g < w.ref_end; ++g, ++all)
      inside += in.ref_x_m[g] >= b.x0_m && in.ref_x_m[g] <= b.x1_m && in.ref_y_m[g] >= b.y0_m &&
                in.ref_y_m[g] <= b.y1_m;
  return all > 0 ? static_cast<double>(inside) / static_cast<double>(all) : 0.0;
}

// A place, not the whole drive (header comment): a box over most of the
// path is a radius error by another name.
bool too_wide(const CrossValidator& cv, const ZoneBox& b, const ZoneSearchOptions& o) {
  return inside_share(cv.input(), cv.windows(), b) > o.max_share;
}

// `s` with slip_zone on over box b (its slips as in `s`).
EffectSet with_box(const EffectSet& s, const ZoneBox& b) {
  EffectSet st = s;
  st.enable(Effect::slip_zone);
  st.set(Effect::slip_zone, "x0", b.x0_m).set(Effect::slip_zone, "x1", b.x1_m);
  st.set(Effect::slip_zone, "y0", b.y0_m).set(Effect::slip_zone, "y1", b.y1_m);
  return st;
}

// A box's cost: the current set's fit cost (0 here) minus what its slips
// remove, fitted alone on the windows that come near the box (elsewhere
// the slips act nowhere and no window's cost changes). A box's cost is
// measured from the windows' settled costs without slip (`settled`, the same
// for every box: slips at no-op act nowhere), so that its fit may start from
// the best box's slips so far (`warm`).
struct BoxTrial {
  CrossValidator& cv;
  const EffectSet& s;
  const SetEval& cur_full;
  const std::vector<double>& settled;
  const ZoneSearchOptions& o;

  // The set with box b; `cost` its cost (infinite when no window comes near
  // or the fit fails), `fitted` its fitted effects.
  EffectSet operator()(const ZoneBox& b, const EffectSet& warm, double& cost, EffectSet& fitted) const {
    EffectSet st = with_box(s, b);
    cost = kInf;
    const std::vector<int> near = windows_near(cv, cur_full, b, kZoneReachM);
    if (near.empty()) return st;
    try {
      const FitSummary f = cv.screen(start_from(st, warm), Effect::slip_zone, near, o.max_iterations);
      double base = 0.0;
      for (int w : f.fitted_windows) base += settled[static_cast<std::size_t>(w)];
      if (std::isfinite(f.final_cost)) {
        cost = f.final_cost - base;
        fitted = f.effects;
      }
    } catch (const std::exception&) {
    }
    return st;
  }
};

// The box being refined: its set, fitted effects (the next fits' warm
// start), box and cost.
struct BoxState {
  EffectSet best, warm;
  ZoneBox bb;
  double best_cost = kInf;
};

// Coordinate search, first improvement in the order (edge, sign). The
// moves left in a round are fitted speculatively in parallel from the
// current box and warm start; the first that improves is taken and the
// moves after it are fitted again from the new box: the same boxes, starts
// and results as one move at a time, for any number of threads.
void refine_box(const BoxTrial& try_box, const ZoneSearchOptions& o, BoxState& st) {
  struct Move {
    int edge;
    double sign;
  };
  // Steps from half the cell the box was proposed on (coarser grids give
  // coarser boxes) down to a quarter of cell_m.
  std::vector<double> steps;
  for (double step = 0.5 * std::max(st.bb.cell_m, o.cell_m); step > 0.2 * o.cell_m; step *= 0.5)
    steps.push_back(step);
  for (double step : steps)
    for (int round = 0, moved = 1; moved && round < 4; ++round) {
      moved = 0;
      std::vector<Move> left;
      for (int edge = 0; edge < 4; ++edge)
        for (double sign : {-1.0, 1.0}) left.push_back({edge, sign});
      while (!left.empty()) {
        std::vector<ZoneBox> qs;
        for (const Move& m : left) {
          ZoneBox q = st.bb;
          double* v[4] = {&q.x0_m, &q.x1_m, &q.y0_m, &q.y1_m};
          *v[m.edge] += m.sign * step;
          qs.push_back(q);
        }
        std::vector<double> costs(qs.size(), kInf);
        std::vector<EffectSet> sets(qs.size()), fits(qs.size());
        // try_box reads `st.warm`, which no task writes.
#pragma omp parallel for schedule(dynamic, 1) if (qs.size() > 1)
        for (std::size_t i = 0; i < qs.size(); ++i)
          if (qs[i].x0_m < qs[i].x1_m && qs[i].y0_m < qs[i].y1_m && !too_wide(try_box.cv, qs[i], o))
            sets[i] = try_box(qs[i], st.warm, costs[i], fits[i]);
        std::size_t taken = qs.size();
        for (std::size_t i = 0; i < qs.size() && taken == qs.size(); ++i)
          if (costs[i] < st.best_cost - 1e-6 * std::abs(st.best_cost)) taken = i;
        if (taken == qs.size()) break;
        st.best_cost = costs[taken];
        st.best = sets[taken];
        st.bb = qs[taken];
        st.warm = fits[taken];
        moved = 1;
        left.erase(left.begin(), left.begin() + static_cast<long>(taken) + 1);
      }
    }
}

// Undetermined edges (select.h): each edge in turn is moved out to the
// isotropic patch, by the whole way, else half or a quarter of it, kept
// when the fit cost rises by less than kFlatCost.
void open_flat_edges(const BoxTrial& try_box, const ZoneSearchOptions& o, BoxState& st) {
  ZoneBox& bb = st.bb;
  const double side = std::max(bb.x1_m - bb.x0_m, bb.y1_m - bb.y0_m);
  const double ref_cost = st.best_cost;
  for (int edge = 0; edge < 4; ++edge) {
    const double c = inside_centre(try_box.cv.input(), try_box.cv.windows(), bb, edge / 2);
    if (!std::isfinite(c)) break;
    double* v[4] = {&bb.x0_m, &bb.x1_m, &bb.y0_m, &bb.y1_m};
    const double target = edge % 2 == 0 ? std::min(*v[edge], c - 0.5 * side)
                                        : std::max(*v[edge], c + 0.5 * side);
    if (!(std::abs(target - *v[edge]) > 0.25 * o.cell_m)) continue;
    // The whole and half way fitted at once (parallel), then the quarter
    // way if neither stays flat; the first that stays flat is kept.
    const double fracs[3] = {1.0, 0.5, 0.25};
    ZoneBox qs[3];
    double costs[3] = {kInf, kInf, kInf};
    EffectSet sets[3], fits[3];
    for (int i = 0; i < 3; ++i) {
      qs[i] = bb;
      double* qv[4] = {&qs[i].x0_m, &qs[i].x1_m, &qs[i].y0_m, &qs[i].y1_m};
      *qv[edge] += fracs[i] * (target - *v[edge]);
    }
#pragma omp parallel for schedule(dynamic, 1)
    for (int i = 0; i < 2; ++i) sets[i] = try_box(qs[i], st.warm, costs[i], fits[i]);
    if (!(costs[0] <= ref_cost + kFlatCost || costs[1] <= ref_cost + kFlatCost))
      sets[2] = try_box(qs[2], st.warm, costs[2], fits[2]);
    for (int i = 0; i < 3; ++i)
      if (costs[i] <= ref_cost + kFlatCost) {
        st.best = sets[i];
        bb = qs[i];
        break;
      }
  }
}

}  // namespace

EffectSet choose_zone_box(CrossValidator& cv, const EffectSet& s, const SetEval& cur_full,
                          const ZoneSearchOptions& o) {
  std::vector<ZoneBox> boxes = zone_candidates(cv.input(), cv.windows(), cur_full.pred.x_m, cur_full.pred.y_m,
                                               cur_full.pred.theta_rad, o.cell_m, o.max_boxes, o.min_score);
  boxes.insert(boxes.end(), o.extra_boxes.begin(), o.extra_boxes.end());
  boxes.erase(std::remove_if(boxes.begin(), boxes.end(), [&](const ZoneBox& b) { return too_wide(cv, b, o); }),
              boxes.end());
  const EffectSet& start = cur_full.fitted;
  std::vector<double> settled;
  if (!boxes.empty()) {
    const EffectSet at = with_box(start_from(s, start), boxes[0]);
    try {
      settled = cv.settled_costs(at, Effect::slip_zone);
    } catch (const std::exception&) {
      return {};
    }
  }
  const BoxTrial try_box{cv, s, cur_full, settled, o};
  BoxState st;
  EffectSet best_fit;
  {  // every candidate box from the same start, in parallel; the first lowest cost wins
    std::vector<double> costs(boxes.size(), kInf);
    std::vector<EffectSet> sets(boxes.size()), fits(boxes.size());
#pragma omp parallel for schedule(dynamic, 1) if (boxes.size() > 1)
    for (std::size_t i = 0; i < boxes.size(); ++i) sets[i] = try_box(boxes[i], start, costs[i], fits[i]);
    for (std::size_t i = 0; i < boxes.size(); ++i)
      if (costs[i] < st.best_cost) {
        st.best_cost = costs[i];
        st.best = sets[i];
        best_fit = fits[i];
        st.bb = boxes[i];
      }
  }
  if (st.best.empty()) return st.best;
  if (std::max(best_fit.get(Effect::slip_zone, "s_l"), best_fit.get(Effect::slip_zone, "s_r")) < kMinZoneSlip &&
      !(-st.best_cost >= kRefineCost))
    return st.best;
  st.warm = best_fit;
  refine_box(try_box, o, st);
  open_flat_edges(try_box, o, st);
  return st.best;
}

}  // namespace odotune::diagnose
