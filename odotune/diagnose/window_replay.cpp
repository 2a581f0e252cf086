#include <odotune/diagnose/window_replay.h>

#include <odotune/core/robust_stats.h>
#include <odotune/diagnose/series_interp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

namespace odotune::diagnose {

namespace {

constexpr double kTimeEps = 1e-9;  // [s] tolerance of window boundaries
constexpr double kMaxWindows = 1e6;

// A rigid 2D motion: rotation about the origin, then translation.
struct Rigid {
  double phi = 0.0, tx = 0.0, ty = 0.0;  // p -> R(phi) p + t
  Pose<double> apply(const Pose<double>& p) const {
    const double c = std::cos(phi), s = std::sin(phi);
    return {c * p.x - s * p.y + tx, s * p.x + c * p.y + ty, p.th + phi};
  }
};

// The rigid motion that best maps `pred` onto the reference of w in least
// squares: positions only, or positions and headings weighted by the
// reference sigmas (file comment of window_replay.h).
Rigid align(const std::vector<Pose<double>>& pred, const DiagInput& in, const Window& w, bool heading) {
  // Each sample weighted by DiagInput::ref_weight (1 with one reference source).
  const std::size_t n = pred.size();
  double px = 0, py = 0, qx = 0, qy = 0, sw = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double wi = in.ref_weight(w.ref_begin + i);
    px += wi * pred[i].x;
    py += wi * pred[i].y;
    qx += wi * in.ref_x_m[w.ref_begin + i];
    qy += wi * in.ref_y_m[w.ref_begin + i];
    sw += wi;
  }
  px /= sw;
  py /= sw;
  qx /= sw;
  qy /= sw;
  double c = 0, s = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double wi = in.ref_weight(w.ref_begin + i);
    const double ax = pred[i].x - px, ay = pred[i].y - py;
    const double bx = in.ref_x_m[w.ref_begin + i] - qx, by = in.ref_y_m[w.ref_begin + i] - qy;
    c += wi * (ax * bx + ay * by);
    s += wi * (ax * by - ay * bx);
  }
  double phi = (c == 0.0 && s == 0.0) ? 0.0 : std::atan2(s, c);
  if (heading) {
    // f(phi) = -2 (c cos phi + s sin phi)/sm2 + sum (phi - m_i)^2/sh2 (+ const),
    // m_i = thref_i - th_i: Newton steps from the position-only solution
    // (f is convex near it: f'' = 2 (c cos + s sin)/sm2 + 2 n/sh2 > 0 there).
    double m = 0.0;
    for (std::size_t i = 0; i < n; ++i) m += in.ref_theta_rad[w.ref_begin + i] - pred[i].th;
    m /= static_cast<double>(n);
    const double wm = 1.0 / (in.ref_sigma_m * in.ref_sigma_m);
    const double wh = static_cast<double>(n) / (in.ref_sigma_rad * in.ref_sigma_rad);
    if (c == 0.0 && s == 0.0) phi = m;
    for (int it = 0; it < 20; ++it) {
      const double cs = std::cos(phi), sn = std::sin(phi);
      const double g = wm * (c * sn - s * cs) + wh * (phi - m);
      const double h = wm * (c * cs + s * sn) + wh;
      if (!(h > 0.0)) break;
      const double step = g / h;
      phi -= step;
      if (std::abs(step) < 1e-12) break;
    }
    if (!std::isfinite(phi)) phi = m;
  }
  const double cp = std::cos(phi), sp = std::sin(phi);
  return {phi, qx - (cp * px - sp * py), qy - (sp * px + cp * py)};
}

}  // namespace

std::vector<double> window_starts(const DiagInput& in, double window_s) {
  if (!(std::isfinite(window_s) && window_s >= 0.0))
    throw std::invalid_argument(fmt::format("window_s = {}; expected a number >= 0 s (0 = one window)",
                                            window_s));
  const auto& ot = in.odo_t_s;
  const auto& rt = in.ref_t_s;
  if (ot.size() < 2 || rt.empty())
    throw std::invalid_argument(fmt::format("track '{}': no odometry or no reference to window",
                                            in.track_name));
  if (!in.fixed_window_starts_s.empty() && window_s == in.fixed_window_s) return in.fixed_window_starts_s;
  const double t0 = std::max(ot.front(), rt.front()), t_last = rt.back();
  const bool heading = in.has_ref_heading();
  double count = 1.0;
  if (window_s > 0.0) count = std::max(1.0, std::ceil((t_last - t0) / window_s - 1e-9));
  if (count > kMaxWindows)
    throw std::invalid_argument(fmt::format("window_s = {} s cuts {:.0f} s into {:.3g} windows; "
                                            "expected at most {:.0g}",
                                            window_s, t_last - t0, count, kMaxWindows));
  const auto n_win = static_cast<std::size_t>(count);
  // A reference with gaps: a gap longer than two
  // reference periods ends a window at its last sample before the gap and
  // starts the next at its first sample after it, so that no window dead-
  // reckons across a gap and every anchor is a measured pose, not one
  // interpolated across the gap. Window boundaries: the nominal starts t0 +
  // j*window_s plus the first sample after each gap.
  double gap_s = std::numeric_limits<double>::infinity();
  if (heading && rt.size() >= 2) gap_s = 2.0 * core::median_period_s(rt, core::MedianRule::upper_middle);
  std::vector<double> starts;
  for (std::size_t j = 0; j < n_win; ++j) starts.push_back(t0 + static_cast<double>(j) * window_s);
  if (std::isfinite(gap_s)) {
    // Only a gap longer than a quarter window ends one: dead reckoning across
    // a short dropout is harmless, and a recording with frequent dropouts
    // (MRCLAM's Vicon) must not be cut into windows too short to show drift.
    const double split_s = std::max(gap_s, 0.25 * window_s);
    for (std::size_t i = 0; i + 1 < rt.size(); ++i)
      if (rt[i + 1] - rt[i] > split_s && rt[i + 1] > t0) starts.push_back(rt[i + 1]);
    std::sort(starts.begin(), starts.end());
    // A nominal start inside a gap moves to the gap's end (already a start).
    std::vector<double> kept;
    for (double st : starts) {
      const auto first = std::lower_bound(rt.begin(), rt.end(), st - kTimeEps);
      const double moved = first != rt.end() && *first - st > gap_s ? *first : st;
      if (kept.empty() || moved > kept.back() + kTimeEps) kept.push_back(moved);
    }
    starts = std::move(kept);
  }
  return starts;
}

std::vector<Window> make_windows(const DiagInput& in, double window_s) {
  const std::vector<double> starts = window_starts(in, window_s);
  const auto& ot = in.odo_t_s;
  const auto& rt = in.ref_t_s;
  const double t_last = rt.back();
  const bool heading = in.has_ref_heading();
  const std::size_t min_ref = heading ? 1 : 3;
  std::vector<Window> out;
  for (std::size_t j = 0; j < starts.size(); ++j) {
    const double s = starts[j];
    const bool last = j + 1 == starts.size();
    const double e = last ? std::numeric_limits<double>::infinity() : starts[j + 1];
    Window w;
    w.node_begin = static_cast<std::size_t>(std::lower_bound(ot.begin(), ot.end(), s - kTimeEps) - ot.begin());
    if (w.node_begin + 1 >= ot.size()) continue;
    w.t_begin_s = ot[w.node_begin];
    w.t_end_s = std::min(e, t_last);
    w.ref_begin = static_cast<std::size_t>(
        (heading ? std::upper_bound(rt.begin(), rt.end(), w.t_begin_s + kTimeEps)
                 : std::lower_bound(rt.begin(), rt.end(), w.t_begin_s - kTimeEps)) -
        rt.begin());
    w.ref_end = last ? rt.size()
                     : static_cast<std::size_t>(std::lower_bound(rt.begin(), rt.end(), e - kTimeEps) -
                                                rt.begin());
    if (w.ref_end <= w.ref_begin || w.ref_end - w.ref_begin < min_ref) continue;
    w.node_end = static_cast<std::size_t>(std::lower_bound(ot.begin(), ot.end(), rt[w.ref_end - 1] - kTimeEps) -
                                          ot.begin());
    w.node_end = std::clamp(w.node_end, w.node_begin, ot.size() - 1);
    w.index = static_cast<int>(out.size());
    out.push_back(w);
  }
  if (out.empty())
    throw std::invalid_argument(
        fmt::format("track '{}': no window of {} s holds {} reference sample(s) to score", in.track_name,
                    window_s, min_ref));
  return out;
}

Pose<double> reference_pose_at(const DiagInput& in, double t_s) {
  if (!in.has_ref_heading())
    throw std::invalid_argument(fmt::format("track '{}': the reference has no heading", in.track_name));
  return {interp_held(in.ref_t_s, in.ref_x_m, t_s), interp_held(in.ref_t_s, in.ref_y_m, t_s),
          interp_held(in.ref_t_s, in.ref_theta_rad, t_s)};
}

namespace {

// The free anchor of window w: the start pose that best aligns the replay
// with the reference (rigidly, align()); `pred` is left as the replay from it.
// Dead reckoning commutes with a rigid motion of its start, except
// slip_zone's inside test: moved poses are exact without slip_zone, and with
// it the replay is redone from the moved anchor (3 rounds).
Pose<double> free_anchor_of(const EffectModel& model, const std::vector<double>& params, const DiagInput& in,
                            const Window& w, std::vector<Pose<double>>& pred) {
  const bool heading = in.has_ref_heading();
  Pose<double> a = heading ? reference_pose_at(in, w.t_begin_s)
                           : Pose<double>{in.ref_x_m[w.ref_begin], in.ref_y_m[w.ref_begin], 0.0};
  const bool zone = model.structure().on(Effect::slip_zone);
  replay_window(model, params.data(), w, a, in.ref_t_s, pred.data());
  for (int it = 0; it < (zone ? 3 : 1); ++it) {
    const Rigid m = align(pred, in, w, heading);
    a = m.apply(a);
    if (zone)
      replay_window(model, params.data(), w, a, in.ref_t_s, pred.data());
    else
      for (Pose<double>& q : pred) q = m.apply(q);
  }
  return a;
}

}  // namespace

ReplayResult replay(const EffectModel& model, const std::vector<double>& params, const DiagInput& in,
                    const std::vector<Window>& windows, const std::vector<int>& which,
                    const std::vector<Pose<double>>* anchors) {
  return replay(model, params, in, windows, which, anchors, anchoring(in));
}

ReplayResult replay(const EffectModel& model, const std::vector<double>& params, const DiagInput& in,
                    const std::vector<Window>& windows, const std::vector<int>& which,
                    const std::vector<Pose<double>>* anchors, Anchoring mode) {
  if (params.size() != model.layout().size())
    throw std::invalid_argument(fmt::format("replay: {} parameters for a model of {}", params.size(),
                                            model.layout().size()));
  if (model.num_nodes() != in.odo_t_s.size())
    throw std::invalid_argument("replay: the model was built for another track");
  std::vector<int> list = which;
  if (list.empty())
    for (const Window& w : windows) list.push_back(w.index);
  const bool heading = in.has_ref_heading();
  const bool free_anchor = mode == Anchoring::free;
  if (!free_anchor && !heading)
    throw std::invalid_argument(fmt::format("replay: track '{}' has no reference heading to anchor windows on",
                                            in.track_name));
  if (anchors && free_anchor && anchors->size() != list.size())
    throw std::invalid_argument(fmt::format("replay: {} anchors for {} windows", anchors->size(), list.size()));
  const double nan = std::nan("");
  ReplayResult res;
  res.pred_x_m.assign(in.ref_t_s.size(), nan);
  res.pred_y_m.assign(in.ref_t_s.size(), nan);
  res.pred_theta_rad.assign(in.ref_t_s.size(), nan);
  double sum_p = 0.0, sum_h = 0.0;
  std::size_t n_all = 0;
  for (std::size_t i = 0; i < list.size(); ++i) {
    if (list[i] < 0 || static_cast<std::size_t>(list[i]) >= windows.size())
      throw std::invalid_argument(fmt::format("replay: window {} does not exist (the track has {})", list[i],
                                              windows.size()));
    const Window& w = windows[static_cast<std::size_t>(list[i])];
    std::vector<Pose<double>> pred(w.ref_end - w.ref_begin);
    Pose<double> a;
    if (!free_anchor) {
      a = reference_pose_at(in, w.t_begin_s);
    } else if (anchors) {
      a = (*anchors)[i];
    } else {
      a = free_anchor_of(model, params, in, w, pred);
    }
    if (!free_anchor || anchors) replay_window(model, params.data(), w, a, in.ref_t_s, pred.data());
    res.anchors.push_back(a);
    WindowError e{.window = w.index,
                  .t_begin_s = w.t_begin_s,
                  .t_end_s = w.t_end_s,
                  .n_ref = pred.size(),
                  .pos_rmse_m = 0.0,
                  .heading_rmse_rad = heading ? 0.0 : nan};
    double sp = 0.0, sh = 0.0;
    for (std::size_t r = 0; r < pred.size(); ++r) {
      const std::size_t g = w.ref_begin + r;
      const double dx = pred[r].x - in.ref_x_m[g], dy = pred[r].y - in.ref_y_m[g];
      sp += dx * dx + dy * dy;
      res.pred_x_m[g] = pred[r].x;
      res.pred_y_m[g] = pred[r].y;
      res.pred_theta_rad[g] = pred[r].th;
      if (heading) {
        const double dh = pred[r].th - in.ref_theta_rad[g];
        sh += dh * dh;
      }
    }
    const auto n = static_cast<double>(pred.size());
    e.pos_rmse_m = std::sqrt(sp / n);
    if (heading) e.heading_rmse_rad = std::sqrt(sh / n);
    sum_p += sp;
    sum_h += sh;
    n_all += pred.size();
    res.windows.push_back(e);
  }
  const auto nd = static_cast<double>(std::max<std::size_t>(n_all, 1));
  res.pos_rmse_m = std::sqrt(sum_p / nd);
  res.heading_rmse_rad = heading ? std::sqrt(sum_h / nd) : nan;
  return res;
}

ReplayResult replay(const DiagInput& in, const EffectSet& set, double window_s, const std::vector<int>& which,
                    const ModelOptions& opt) {
  const EffectModel model(in, set, opt);
  return replay(model, pack(set), in, make_windows(in, window_s), which);
}

double normalised_sq_distance(const DiagInput& in, const Window& w, const PoseSamples& a, const PoseSamples& b,
                              bool heading) {
  const double ism = 1.0 / in.ref_sigma_m, ish = heading ? 1.0 / in.ref_sigma_rad : 0.0;
  double sum = 0.0;
  for (std::size_t g = w.ref_begin; g < w.ref_end; ++g) {
    const double dx = a.x_m[g] - b.x_m[g], dy = a.y_m[g] - b.y_m[g];
    const double dh = heading ? a.theta_rad[g] - b.theta_rad[g] : 0.0;
    sum += (dx * dx + dy * dy) * ism * ism * in.ref_weight(g) + dh * dh * ish * ish;
  }
  return sum;
}

}  // namespace odotune::diagnose
