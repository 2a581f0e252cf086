#include <odotune/diagnose/locate.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <numeric>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include <odotune/core/non_finite.h>
#include <odotune/core/robust_stats.h>
#include <odotune/core/why.h>
#include <odotune/diagnose/option_rules.h>

namespace odotune::diagnose {
namespace {

using core::kNaN;

// Average ranks (ties share their mean rank).
std::vector<double> ranks(const std::vector<double>& v) {
  std::vector<std::size_t> order(v.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return v[a] < v[b]; });
  std::vector<double> r(v.size());
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j + 1 < order.size() && v[order[j + 1]] == v[order[i]]) ++j;
    const double mean_rank = 0.5 * static_cast<double>(i + j);
    for (std::size_t k = i; k <= j; ++k) r[order[k]] = mean_rank;
    i = j + 1;
  }
  return r;
}

double spearman(const std::vector<double>& a, const std::vector<double>& b) {
  const std::vector<double> ra = ranks(a), rb = ranks(b);
  const double n = static_cast<double>(a.size());
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < ra.size(); ++i) {
    ma += ra[i];
    mb += rb[i];
  }
  ma /= n;
  mb /= n;
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < ra.size(); ++i) {
    sab += (ra[i] - ma) * (rb[i] - mb);
    saa += (ra[i] - ma) * (ra[i] - ma);
    sbb += (rb[i] - mb) * (rb[i] - mb);
  }
  return (saa > 0 && sbb > 0) ? sab / std::sqrt(saa * sbb) : 0.0;
}

struct Youden {
  double threshold = kNaN, j = 0.0;
};

// Best threshold (5 %…95 % quantiles) for "flagged rows lie above/below".
Youden best_threshold(const std::vector<double>& c, const std::vector<std::uint8_t>& flag, bool above) {
  Youden best;
  std::size_t nf = 0;
  for (auto f : flag) nf += f;
  const std::size_t nu = flag.size() - nf;
  if (nf == 0 || nu == 0) return best;
  std::vector<double> sorted = c;
  std::sort(sorted.begin(), sorted.end());
  for (int q = 1; q <= 19; ++q) {
    const double thr = sorted[static_cast<std::size_t>(q * 0.05 * static_cast<double>(sorted.size() - 1))];
    std::size_t f_beyond = 0, u_beyond = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
      const bool beyond = above ? c[i] > thr : c[i] < thr;
      if (beyond) (flag[i] ? f_beyond : u_beyond)++;
    }
    const double j = static_cast<double>(f_beyond) / static_cast<double>(nf) -
                     static_cast<double>(u_beyond) / static_cast<double>(nu);
    if (j > best.j) {
      best.j = j;
      best.threshold = thr;
    }
  }
  return best;
}

std::string number(double v) { return fmt::format("{:.2g}", v); }

std::string condition_phrase(Condition c, bool above, double thr) {
  switch (c) {
    case Condition::speed: return fmt::format("speeds {} {} m/s", above ? "above" : "below", number(thr));
    case Condition::turn_rate:
      return above ? fmt::format("turns faster than {} rad/s", number(thr))
                   : fmt::format("turn rates below {} rad/s", number(thr));
    case Condition::turn_speed:
      return fmt::format("turns at speed (|v*w| {} {} m/s^2)", above ? "above" : "below", number(thr));
    case Condition::acceleration:
      return fmt::format("accelerations {} {} m/s^2", above ? "above" : "below", number(thr));
    case Condition::x: return fmt::format("x {} {} m", above ? "above" : "below", number(thr));
    case Condition::y: return fmt::format("y {} {} m", above ? "above" : "below", number(thr));
    case Condition::time: return fmt::format("{} t = {:.0f} s", above ? "after" : "before", thr);
  }
  return {};
}

void check_series(const ResidualSeries& s) {
  std::string why;
  if (!s.IsValid(&why)) throw std::invalid_argument("locate: residual series: " + why);
}

// Growth rates d_i (x, y, θ) over the centred span (shifted to fit at window
// edges); NaN where undefined. Each is multiplied by dt_i / dt_ref (dt_i its
// actual span, dt_ref the median one) so that all rows share one noise
// level (white-noise law: σ ∝ 1/dt).
struct Growth {
  std::vector<double> dx, dy, dth;
  std::vector<std::size_t> later;  // first row more than one span later, same window (kNone if none)
};
constexpr std::size_t kNone = static_cast<std::size_t>(-1);

Growth growth(const ResidualSeries& s, double span) {
  const std::size_t n = s.t_s.size();
  const bool heading = !s.e_theta_rad.empty();
  Growth g{std::vector<double>(n, kNaN), std::vector<double>(n, kNaN), std::vector<double>(n, kNaN),
           std::vector<std::size_t>(n, kNone)};
  std::vector<double> used(n, kNaN);  // dt_i
  const auto t0 = s.t_s.begin();
  std::size_t w0 = 0;  // first row of the current window
  while (w0 < n) {
    std::size_t w1 = w0;
    while (w1 < n && s.window[w1] == s.window[w0]) ++w1;  // [w0, w1)
    const double tw0 = s.t_s[w0], tw1 = s.t_s[w1 - 1];
    const auto wb = t0 + static_cast<std::ptrdiff_t>(w0), we = t0 + static_cast<std::ptrdiff_t>(w1);
    for (std::size_t i = w0; i < w1; ++i) {
      double lo = s.t_s[i] - 0.5 * span, hi = s.t_s[i] + 0.5 * span;
      if (lo < tw0) lo = tw0, hi = std::min(tw1, tw0 + span);
      if (hi > tw1) hi = tw1, lo = std::max(tw0, tw1 - span);
      const std::size_t a = static_cast<std::size_t>(std::lower_bound(wb, we, lo - 1e-9 * span) - t0);
      const std::size_t b = static_cast<std::size_t>(std::upper_bound(wb, we, hi + 1e-9 * span) - t0) - 1;
      const double dt = b > a ? s.t_s[b] - s.t_s[a] : 0.0;
      if (dt >= 0.5 * span * (1 - 1e-9)) {
        used[i] = dt;
        g.dx[i] = (s.ex_m[b] - s.ex_m[a]) / dt;
        g.dy[i] = (s.ey_m[b] - s.ey_m[a]) / dt;
        if (heading) g.dth[i] = (s.e_theta_rad[b] - s.e_theta_rad[a]) / dt;
      }
      const auto it = std::upper_bound(t0 + static_cast<std::ptrdiff_t>(i), we, s.t_s[i] + span * (1 + 1e-9));
      if (it != we) g.later[i] = static_cast<std::size_t>(it - t0);
    }
    w0 = w1;
  }
  std::vector<double> finite_dt;
  for (double d : used)
    if (std::isfinite(d)) finite_dt.push_back(d);
  const double ref = core::median(finite_dt);
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(used[i])) continue;
    const double f = used[i] / ref;
    g.dx[i] *= f;
    g.dy[i] *= f;
    if (heading) g.dth[i] *= f;
  }
  return g;
}

// σ of a growth component from differences one span apart (file comment).
double growth_sigma(const Growth& g, const std::vector<const std::vector<double>*>& comps) {
  std::vector<double> diffs;
  for (const auto* c : comps) {
    for (std::size_t i = 0; i < c->size(); ++i) {
      const std::size_t j = g.later[i];
      if (j == kNone || !std::isfinite((*c)[i]) || !std::isfinite((*c)[j])) continue;
      diffs.push_back((*c)[j] - (*c)[i]);
    }
  }
  return diffs.size() < 4 ? kNaN : core::robust_sigma(diffs) / std::sqrt(2.0);
}

std::vector<TimeSegment> segments(const ResidualSeries& s, const Location& loc, const LocateOptions& o) {
  std::vector<TimeSegment> raw;
  for (std::size_t i = 0; i < loc.flagged.size(); ++i) {
    if (!loc.flagged[i]) continue;
    if (!raw.empty() && s.t_s[i] - raw.back().t1_s < o.merge_gap_s) {
      raw.back().t1_s = s.t_s[i];
      raw.back().peak_z = std::max(raw.back().peak_z, loc.z[i]);
      ++raw.back().flagged;
    } else {
      raw.push_back({s.t_s[i], s.t_s[i], loc.z[i], 1});
    }
  }
  std::vector<TimeSegment> out;
  for (const auto& seg : raw) {
    if (seg.t1_s - seg.t0_s >= o.min_segment_s && seg.flagged >= o.min_segment_samples) out.push_back(seg);
  }
  return out;
}

std::vector<MapRegion> regions(const ResidualSeries& s, const Location& loc, const LocateOptions& o) {
  std::vector<std::size_t> rows;
  for (std::size_t i = 0; i < loc.z.size(); ++i)
    if (std::isfinite(loc.z[i])) rows.push_back(i);
  if (rows.empty() || loc.flagged_count == 0) return {};
  double x0 = s.x_m[rows[0]], x1 = x0, y0 = s.y_m[rows[0]], y1 = y0;
  for (std::size_t i : rows) {
    x0 = std::min(x0, s.x_m[i]);
    x1 = std::max(x1, s.x_m[i]);
    y0 = std::min(y0, s.y_m[i]);
    y1 = std::max(y1, s.y_m[i]);
  }
  const double cell = std::max({o.cell_m, (x1 - x0) / o.max_cells_per_axis, (y1 - y0) / o.max_cells_per_axis});
  const int nx = static_cast<int>(std::floor((x1 - x0) / cell)) + 1;
  const int ny = static_cast<int>(std::floor((y1 - y0) / cell)) + 1;
  std::vector<int> count(static_cast<std::size_t>(nx * ny), 0), flag(count.size(), 0);
  auto cell_of = [&](std::size_t i) {
    const int cx = std::min(nx - 1, static_cast<int>((s.x_m[i] - x0) / cell));
    const int cy = std::min(ny - 1, static_cast<int>((s.y_m[i] - y0) / cell));
    return static_cast<std::size_t>(cy) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(cx);
  };
  for (std::size_t i : rows) {
    const std::size_t c = cell_of(i);
    ++count[c];
    flag[c] += loc.flagged[i];
  }
  const double overall = static_cast<double>(loc.flagged_count) / static_cast<double>(rows.size());
  const double need = std::max(o.cell_min_flagged_fraction, o.cell_enrichment * overall);
  std::vector<std::uint8_t> hot(count.size(), 0);
  int visited = 0, n_hot = 0;
  for (std::size_t c = 0; c < count.size(); ++c) {
    if (count[c] > 0) ++visited;
    if (count[c] >= o.min_cell_samples && flag[c] >= need * count[c]) {
      hot[c] = 1;
      ++n_hot;
    }
  }
  if (n_hot == 0 || n_hot > o.region_max_cover * visited) return {};
  // 8-connected components of hot cells -> boxes.
  std::vector<MapRegion> out;
  std::vector<std::uint8_t> seen(hot.size(), 0);
  for (std::size_t c0 = 0; c0 < hot.size(); ++c0) {
    if (!hot[c0] || seen[c0]) continue;
    int cx0 = nx, cx1 = -1, cy0 = ny, cy1 = -1;
    MapRegion r;
    std::vector<std::size_t> stack{c0};
    seen[c0] = 1;
    while (!stack.empty()) {
      const std::size_t c = stack.back();
      stack.pop_back();
      const int cx = static_cast<int>(c) % nx, cy = static_cast<int>(c) / nx;
      cx0 = std::min(cx0, cx);
      cx1 = std::max(cx1, cx);
      cy0 = std::min(cy0, cy);
      cy1 = std::max(cy1, cy);
      ++r.cells;
      r.samples += count[c];
      r.flagged += flag[c];
      for (int ddy = -1; ddy <= 1; ++ddy) {
        for (int ddx = -1; ddx <= 1; ++ddx) {
          const int ex = cx + ddx, ey = cy + ddy;
          if (ex < 0 || ey < 0 || ex >= nx || ey >= ny) continue;
          const std::size_t e = static_cast<std::size_t>(ey) * static_cast<std::size_t>(nx) +
                                static_cast<std::size_t>(ex);
          if (hot[e] && !seen[e]) {
            seen[e] = 1;
            stack.push_back(e);
          }
        }
      }
    }
    r.x0_m = x0 + cx0 * cell;
    r.x1_m = x0 + (cx1 + 1) * cell;
    r.y0_m = y0 + cy0 * cell;
    r.y1_m = y0 + (cy1 + 1) * cell;
    out.push_back(r);
  }
  std::sort(out.begin(), out.end(),
            [](const MapRegion& a, const MapRegion& b) { return a.flagged > b.flagged; });
  return out;
}

void rank_conditions(const ResidualSeries& s, Location& loc, const LocateOptions& o) {
  std::vector<std::size_t> rows;
  for (std::size_t i = 0; i < loc.z.size(); ++i)
    if (std::isfinite(loc.z[i])) rows.push_back(i);
  if (rows.size() < 3) return;
  std::vector<double> z(rows.size());
  std::vector<std::uint8_t> flag(rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    z[k] = loc.z[rows[k]];
    flag[k] = loc.flagged[rows[k]];
  }
  std::array<std::vector<double>, kNumConditions> values;
  for (int c = 0; c < kNumConditions; ++c) {
    values[static_cast<std::size_t>(c)].resize(rows.size());
    for (std::size_t k = 0; k < rows.size(); ++k) {
      values[static_cast<std::size_t>(c)][k] = condition_value(s, static_cast<Condition>(c), rows[k]);
    }
    ConditionRank r;
    r.condition = static_cast<Condition>(c);
    r.rho = spearman(values[static_cast<std::size_t>(c)], z);
    r.above = r.rho >= 0;
    const Youden y = best_threshold(values[static_cast<std::size_t>(c)], flag, r.above);
    r.threshold = y.threshold;
    r.youden_j = y.j;
    loc.conditions.push_back(r);
  }
  std::stable_sort(loc.conditions.begin(), loc.conditions.end(),
                   [](const ConditionRank& a, const ConditionRank& b) {
                     return std::abs(a.rho) > std::abs(b.rho);
                   });

  const ConditionRank& first = loc.conditions.front();
  if (loc.flagged_count == 0 || std::abs(first.rho) < o.min_rank_correlation || first.youden_j < o.min_youden_j)
    return;
  // A second condition among the rows beyond the first threshold.
  const auto& v1 = values[static_cast<std::size_t>(first.condition)];
  std::vector<std::size_t> sub;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    if (first.above ? v1[k] > first.threshold : v1[k] < first.threshold) sub.push_back(k);
  }
  const ConditionRank* second = nullptr;
  Youden best2;
  std::vector<std::uint8_t> f2(sub.size());
  for (std::size_t k = 0; k < sub.size(); ++k) f2[k] = flag[sub[k]];
  for (const ConditionRank& r : loc.conditions) {
    if (r.condition == first.condition || sub.size() < 3) continue;
    // |w| and |v·w| describe the same turning: a second part must add a dimension.
    const bool turning1 = first.condition == Condition::turn_rate || first.condition == Condition::turn_speed;
    const bool turning2 = r.condition == Condition::turn_rate || r.condition == Condition::turn_speed;
    if (turning1 && turning2) continue;
    std::vector<double> v2(sub.size());
    for (std::size_t k = 0; k < sub.size(); ++k) v2[k] = values[static_cast<std::size_t>(r.condition)][sub[k]];
    const Youden y = best_threshold(v2, f2, r.above);
    if (y.j >= o.min_youden_j && y.j > best2.j) {
      best2 = y;
      second = &r;
    }
  }
  std::vector<ConditionPart> parts{{first.condition, first.above, first.threshold}};
  if (second != nullptr) {
    const ConditionPart p2{second->condition, second->above, best2.threshold};
    if (p2.condition == Condition::turn_rate) {
      parts.insert(parts.begin(), p2);
    } else {
      parts.push_back(p2);
    }
  }
  std::string phrase = condition_phrase(parts[0].condition, parts[0].above, parts[0].threshold);
  if (parts.size() == 2) {
    phrase += parts[1].condition == Condition::speed ? " at " : " and ";
    phrase += condition_phrase(parts[1].condition, parts[1].above, parts[1].threshold);
  }
  loc.phrase_parts = std::move(parts);
  loc.phrase = std::move(phrase);
}

}  // namespace

double condition_value(const ResidualSeries& s, Condition c, std::size_t i) {
  switch (c) {
    case Condition::speed: return s.v_mps[i];
    case Condition::turn_rate: return std::abs(s.w_radps[i]);
    case Condition::turn_speed: return std::abs(s.v_mps[i] * s.w_radps[i]);
    case Condition::acceleration: return std::abs(s.accel_mps2[i]);
    case Condition::x: return s.x_m[i];
    case Condition::y: return s.y_m[i];
    case Condition::time: return s.t_since_start_s[i];
  }
  return std::numeric_limits<double>::quiet_NaN();
}

std::string_view condition_name(Condition c) {
  switch (c) {
    case Condition::speed: return "v";
    case Condition::turn_rate: return "|w|";
    case Condition::turn_speed: return "|v*w|";
    case Condition::acceleration: return "|a|";
    case Condition::x: return "x";
    case Condition::y: return "y";
    case Condition::time: return "t";
  }
  return "?";
}

bool ResidualSeries::IsValid(std::string* why) const {
  const std::size_t n = t_s.size();
  if (n == 0) return core::invalid(why, "no rows (expected at least one residual sample)");
  const std::pair<const char*, const std::vector<double>*> cols[] = {{"ex_m", &ex_m},
                                                                     {"ey_m", &ey_m},
                                                                     {"x_m", &x_m},
                                                                     {"y_m", &y_m},
                                                                     {"v_mps", &v_mps},
                                                                     {"w_radps", &w_radps},
                                                                     {"accel_mps2", &accel_mps2},
                                                                     {"t_since_start_s", &t_since_start_s},
                                                                     {"e_theta_rad", &e_theta_rad},
                                                                     {"t_s", &t_s}};
  for (const auto& [name, col] : cols) {
    if (col == &e_theta_rad && col->empty()) continue;
    if (col->size() != n) {
      return core::invalid(why, fmt::format("{} has {} values for {} rows (expected equal lengths)", name,
                                            col->size(), n));
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (!std::isfinite((*col)[i]))
        return core::invalid(why, fmt::format("{}[{}] is not finite (expected a number)", name, i));
    }
  }
  if (window.size() != n) {
    return core::invalid(why, fmt::format("window has {} values for {} rows (expected equal lengths)",
                                          window.size(), n));
  }
  for (std::size_t i = 1; i < n; ++i) {
    if (window[i] < window[i - 1]) {
      return core::invalid(why, fmt::format("window[{}] = {} after {} (expected non-decreasing)", i, window[i],
                                            window[i - 1]));
    }
    const bool same = window[i] == window[i - 1];
    if (same ? !(t_s[i] > t_s[i - 1]) : !(t_s[i] >= t_s[i - 1])) {
      return core::invalid(
          why, fmt::format("t_s[{}] = {} after {} (expected increasing time, strictly within a window)", i,
                           t_s[i], t_s[i - 1]));
    }
  }
  return true;
}

bool LocateOptions::IsValid(std::string* why) const {
  return check_option_rules(
      {
          {is_positive(growth_span_s), "growth_span_s", growth_span_s, "> 0"},
          {min_span_samples >= 2, "min_span_samples", static_cast<double>(min_span_samples), ">= 2"},
          {is_positive(threshold_sigma), "threshold_sigma", threshold_sigma, "> 0"},
          {is_positive(min_sigma_m), "min_sigma_m", min_sigma_m, "> 0"},
          {is_positive(min_sigma_rad), "min_sigma_rad", min_sigma_rad, "> 0"},
          {is_non_negative(merge_gap_s), "merge_gap_s", merge_gap_s, ">= 0"},
          {is_non_negative(min_segment_s), "min_segment_s", min_segment_s, ">= 0"},
          {min_segment_samples >= 1, "min_segment_samples", static_cast<double>(min_segment_samples), ">= 1"},
          {is_positive(cell_m), "cell_m", cell_m, "> 0"},
          {max_cells_per_axis >= 1 && max_cells_per_axis <= 2000, "max_cells_per_axis",
           static_cast<double>(max_cells_per_axis), "in [1, 2000]"},
          {min_cell_samples >= 1, "min_cell_samples", static_cast<double>(min_cell_samples), ">= 1"},
          {is_fraction(cell_min_flagged_fraction), "cell_min_flagged_fraction", cell_min_flagged_fraction,
           "in [0, 1]"},
          {is_non_negative(cell_enrichment), "cell_enrichment", cell_enrichment, ">= 0"},
          {is_fraction(region_max_cover), "region_max_cover", region_max_cover, "in [0, 1]"},
          {is_fraction(min_rank_correlation), "min_rank_correlation", min_rank_correlation, "in [0, 1]"},
          {is_fraction(min_youden_j), "min_youden_j", min_youden_j, "in [0, 1]"},
      },
      why);
}

Location locate(const ResidualSeries& s, double sigma_m, const LocateOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument("locate options: " + why);
  check_series(s);
  if (!(std::isfinite(sigma_m) && sigma_m >= 0)) {
    throw std::invalid_argument(fmt::format("locate: sigma_m = {} (expected a finite value >= 0)", sigma_m));
  }
  const std::size_t n = s.t_s.size();
  std::vector<double> steps;
  for (std::size_t i = 1; i < n; ++i)
    if (s.window[i] == s.window[i - 1]) steps.push_back(s.t_s[i] - s.t_s[i - 1]);
  const double dt = steps.empty() ? 0.0 : core::median(std::move(steps));
  Location loc;
  loc.span_s = std::max(o.growth_span_s, (o.min_span_samples - 1) * dt);
  const Growth g = growth(s, loc.span_s);
  const bool heading = !s.e_theta_rad.empty();

  const double floor_xy = std::max(std::sqrt(2.0) * sigma_m, o.min_sigma_m) / loc.span_s;
  const double est_xy = growth_sigma(g, {&g.dx, &g.dy});
  loc.sigma_growth_mps = std::isfinite(est_xy) ? std::max(est_xy, floor_xy) : floor_xy;
  if (heading) {
    const double floor_th = o.min_sigma_rad / loc.span_s;
    const double est_th = growth_sigma(g, {&g.dth});
    loc.sigma_growth_radps = std::isfinite(est_th) ? std::max(est_th, floor_th) : floor_th;
  }
  loc.z.assign(n, kNaN);
  loc.flagged.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(g.dx[i])) continue;
    double z = std::hypot(g.dx[i], g.dy[i]) / loc.sigma_growth_mps;
    if (heading) z = std::max(z, std::abs(g.dth[i]) / loc.sigma_growth_radps);
    loc.z[i] = z;
    if (z > o.threshold_sigma) {
      loc.flagged[i] = 1;
      ++loc.exceedances;
    }
  }
  loc.segments = segments(s, loc, o);
  // Only exceedances inside kept segments stay flagged.
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    while (k < loc.segments.size() && loc.segments[k].t1_s < s.t_s[i]) ++k;
    const bool inside = k < loc.segments.size() && s.t_s[i] >= loc.segments[k].t0_s;
    if (loc.flagged[i] && !inside) loc.flagged[i] = 0;
    loc.flagged_count += loc.flagged[i];
  }
  loc.regions = regions(s, loc, o);
  rank_conditions(s, loc, o);
  return loc;
}

}  // namespace odotune::diagnose
