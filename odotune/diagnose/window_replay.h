// Windowed dead reckoning of an effect model against the reference
// (docs/diagnosis-design.md step 3; errors as ../shared/specs/diagnosis-output.md):
// the track is cut into windows of window_s seconds, each replayed from an
// anchor pose at its start and scored on the reference samples inside it.
//
// Windows. t0 = the first instant with both odometry and reference; window j
// nominally covers [t0 + j*W, t0 + (j+1)*W) (W = window_s; 0 = one window up
// to the last reference sample, which the last window always includes). It
// starts at the first odometry node at or after its nominal start
// (t_begin_s), the anchor time. With a reference heading, a window whose
// nominal start falls in a gap of the reference (consecutive samples more
// than two median reference periods apart) starts at the first sample after
// it, and a gap longer than a quarter window ends a window at its last
// sample before the gap and starts another at the first sample after it: no
// window dead-reckons across a long gap (a 15 s gap inside a 20 s window
// made one window's error outweigh all others by 10^4), every anchor is a
// measured pose, and short dropouts (MRCLAM's Vicon) do not cut windows
// short. Scored samples: reference samples in the
// nominal span at or after t_begin_s, strictly after it when the reference has
// heading (that sample is the anchor itself). Windows without a scored sample
// (with a free anchor: fewer than 3) are dropped; the rest are numbered 0, 1,
// ... in time order, which is the number train/held-out lists use.
//
// Anchors (Anchoring). `reference` (the default with a reference heading,
// ground truth with gt_theta): the anchor is the reference pose interpolated
// linearly (x, y, unwrapped theta) at t_begin_s. `free` (the default without
// a reference heading: position fixes, or ground truth without heading; and
// on request with one, see below): the anchor is a nuisance parameter, which
// a fit fits and replay() chooses in closed form: the rigid 2D motion that
// maps the dead-reckoned positions onto the window's reference positions in
// least squares (Kabsch/Umeyama without scale), applied to a replay started
// at the window's first reference position with heading 0 (three times with
// slip_zone, whose effect depends on where the robot is). With a reference
// heading the rotation phi minimises the weighted sum
//   sum |R(phi) p_i + t - q_i|^2 / sigma_m^2 + sum (th_i + phi - thref_i)^2 / sigma_rad^2
// (t in closed form for each phi; phi by Newton steps from the position-only
// solution), the replay starting at the reference pose at t_begin_s.
// Why free anchors with ground truth: an anchor on ONE reference pose carries
// that sample's noise into every prediction of the window (a heading error
// d swings the window's end by d*L, a position error shifts it), and a fit
// absorbs that noise into whatever effect grows along the window: on a
// 180 s track with 10 mm / 5 mrad ground truth the two radius scales came out
// ~2e-4 off (more than the whole of a 0.06 % radius error). A free anchor is
// determined by all of the window's samples.
//
// Prediction at a reference time between two odometry nodes: linear
// interpolation of the node poses (x, y, theta).
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/effect_model.h>

namespace odotune::diagnose {

struct Window {
  int index = 0;
  double t_begin_s = 0.0;  // anchor time (an odometry node)
  double t_end_s = 0.0;    // nominal end (the next window's nominal start, or the last sample)
  std::size_t node_begin = 0, node_end = 0;  // odometry nodes replayed, [node_begin, node_end]
  std::size_t ref_begin = 0, ref_end = 0;    // reference samples scored, [ref_begin, ref_end)
};

// Throws std::invalid_argument for window_s < 0 or not finite.
std::vector<Window> make_windows(const DiagInput& in, double window_s);

// The nominal window starts make_windows cuts at [s] (DiagInput::
// fixed_window_starts_s when they are set for window_s); throws as make_windows.
std::vector<double> window_starts(const DiagInput& in, double window_s);

// True when windows are anchored on the reference pose (reference with heading).
inline bool anchored_on_reference(const DiagInput& in) { return in.has_ref_heading(); }

// How a window's anchor pose is chosen (see the file comment).
enum class Anchoring {
  reference,  // the reference pose at t_begin_s (needs a reference heading)
  free,       // a nuisance pose: closed-form alignment in replay(), fitted by fit_effects
};
// `free` when asked (free_with_heading) or when the reference has no heading.
inline Anchoring anchoring(const DiagInput& in, bool free_with_heading = false) {
  return anchored_on_reference(in) && !free_with_heading ? Anchoring::reference : Anchoring::free;
}

// Reference pose interpolated at time t (requires a reference heading).
Pose<double> reference_pose_at(const DiagInput& in, double t_s);

// Dead reckoning of window w from `anchor` (the pose at w.node_begin) with the
// model's flat parameters; out[i] = predicted pose at reference sample
// w.ref_begin + i. `ref_t` is DiagInput::ref_t_s. With `frame`, the poses are
// in a local frame whose origin is the world pose *frame (used by the fit's
// anchor composition): only slip_zone's inside test looks at the world pose,
// and it gets frame (+) pose.
template <typename T>
void replay_window(const EffectModel& model, const T* params, const Window& w, const Pose<T>& anchor,
                   const std::vector<double>& ref_t, Pose<T>* out, const Pose<double>* frame = nullptr) {
  const auto& t = model.series().t_s;
  Stepper<T> stepper(model, params);
  stepper.start(w.node_begin);
  Pose<T> p = anchor;
  const bool world = frame && model.structure().on(Effect::slip_zone);
  const double fc = frame ? std::cos(frame->th) : 1.0, fs = frame ? std::sin(frame->th) : 0.0;
  std::size_t r = w.ref_begin;
  while (r < w.ref_end && ref_t[r] <= t[w.node_begin]) out[r++ - w.ref_begin] = p;
  for (std::size_t k = w.node_begin; k < w.node_end && r < w.ref_end; ++k) {
    const Pose<T> prev = p;
    if (world) {
      const double lx = scalar(prev.x), ly = scalar(prev.y);
      advance(p, stepper.step(k, Pose<T>{T(frame->x + fc * lx - fs * ly), T(frame->y + fs * lx + fc * ly),
                                         prev.th}));
    } else {
      advance(p, stepper.step(k, prev));
    }
    const double h = t[k + 1] - t[k];
    while (r < w.ref_end && ref_t[r] <= t[k + 1]) {
      const double f = (ref_t[r] - t[k]) / h;
      out[r++ - w.ref_begin] = Pose<T>{prev.x + f * (p.x - prev.x), prev.y + f * (p.y - prev.y),
                                       prev.th + f * (p.th - prev.th)};
    }
  }
  while (r < w.ref_end) out[r++ - w.ref_begin] = p;
}

struct WindowError {
  int window = 0;
  double t_begin_s = 0.0, t_end_s = 0.0;
  std::size_t n_ref = 0;          // scored reference samples
  double pos_rmse_m = 0.0;        // sqrt(mean(dx^2 + dy^2))
  double heading_rmse_rad = 0.0;  // sqrt(mean(dtheta^2)); NaN without reference heading
};

struct ReplayResult {
  std::vector<WindowError> windows;   // in the order asked
  double pos_rmse_m = 0.0;            // pooled over every scored sample of those windows
  double heading_rmse_rad = 0.0;      // pooled; NaN without reference heading
  std::vector<Pose<double>> anchors;  // anchor of each replayed window
  // Predicted pose per reference sample (DiagInput::ref_t_s); NaN where no
  // replayed window scores the sample.
  std::vector<double> pred_x_m, pred_y_m, pred_theta_rad;
};

// Position and heading RMSE pooled over the scored samples of windows from
// any number of replays (windows replay independently, so the windows of an
// all-window replay pool to what replaying only them gives).
struct PooledError {
  double sp = 0.0, sh = 0.0, n = 0.0;  // sums of n_ref * rmse^2, and of n_ref
  // n samples of RMSEs pos and heading.
  void add(double pos, double heading, std::size_t samples) {
    const auto k = static_cast<double>(samples);
    sp += k * pos * pos;
    sh += k * heading * heading;
    n += k;
  }
  void add(const WindowError& w) { add(w.pos_rmse_m, w.heading_rmse_rad, w.n_ref); }
  void add(const ReplayResult& r) {
    for (const WindowError& w : r.windows) add(w);
  }
  bool empty() const { return !(n > 0.0); }
  double pos_rmse_m() const { return empty() ? std::nan("") : std::sqrt(sp / n); }
  double heading_rmse_rad() const { return empty() ? std::nan("") : std::sqrt(sh / n); }
};

// Poses per reference sample (DiagInput::ref_t_s) of a prediction, or of the
// reference itself (reference_poses); theta only read with a heading.
struct PoseSamples {
  const std::vector<double>& x_m;
  const std::vector<double>& y_m;
  const std::vector<double>& theta_rad;
};
inline PoseSamples reference_poses(const DiagInput& in) { return {in.ref_x_m, in.ref_y_m, in.ref_theta_rad}; }

// Sum over window w's reference samples g of |a_g - b_g|^2 in reference
// sigmas: position by ref_sigma_m and the sample's weight, plus heading by
// ref_sigma_rad when `heading`. With b = reference_poses(in) it is a's
// normalised SSE; with two predictions, how far one moves from the other.
double normalised_sq_distance(const DiagInput& in, const Window& w, const PoseSamples& a, const PoseSamples& b,
                              bool heading);

// Replays windows `which` (indices into `windows`; empty = all) with the flat
// parameters `params` (layout order of model.layout()). `anchors`, when given,
// holds one anchor per entry of `which` for free-anchor windows (ignored with
// Anchoring::reference); otherwise they are chosen in closed form. The first
// form anchors as anchoring(in). Throws std::invalid_argument for a bad
// window index or parameter count, or Anchoring::reference without a
// reference heading.
ReplayResult replay(const EffectModel& model, const std::vector<double>& params, const DiagInput& in,
                    const std::vector<Window>& windows, const std::vector<int>& which = {},
                    const std::vector<Pose<double>>* anchors = nullptr);
ReplayResult replay(const EffectModel& model, const std::vector<double>& params, const DiagInput& in,
                    const std::vector<Window>& windows, const std::vector<int>& which,
                    const std::vector<Pose<double>>* anchors, Anchoring mode);

// Convenience: builds the model of `set` and the windows of window_s.
ReplayResult replay(const DiagInput& in, const EffectSet& set, double window_s,
                    const std::vector<int>& which = {}, const ModelOptions& opt = {});

}  // namespace odotune::diagnose
