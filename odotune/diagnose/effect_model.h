// The augmented odometry model of the diagnosis (docs/diagnosis-design.md,
// step 2): the nominal kinematics of track-format.md plus any subset of the
// physics effects of ../shared/specs/physics-effects.md, mapping the MEASURED
// odometry of one interval (node k -> k+1 of DiagInput::odo_t_s) to the TRUE
// body motion. It inverts the simulator's world model (docs/simulator.md,
// header comment) step for step, so that a simulated effect is recovered:
//
//  * Source. The odometry becomes, per wheel, the cumulative NOMINAL rim travel
//    S(t) [m] (R_nom*phi for wheel angles; for body velocities the integral of
//    the nominal rim speeds v -+ w*D/2, taken linear between stamps, so S is
//    piecewise quadratic) with slopes U(t) [m/s] at the nodes (the rim speeds;
//    central differences of S for wheel angles). Travel over an interval is
//    S(t_{k+1}) - S(t_k).
//  * time_offset dt: the odometry stamped t was measured at t - dt, so the
//    truth at t is read at t + dt: S(t + dt) by cubic Hermite interpolation of
//    (S, U) between nodes (exact for body velocities, C1 and differentiable in
//    dt; the node values themselves at dt = 0). Outside the odometry's span the
//    first/last value is held, like the simulator.
//  * actuator_lag tau: the true rim speeds follow the commanded ones through
//    d(y)/dt = (c - y)/tau, discretised exactly for c linear over an interval
//    (first-order hold, as the simulator), travel = h*(y_k + y_{k+1})/2. The
//    lag acts on commands only: with wheel odometry the encoders already
//    measure the lagged wheels, so an EffectSet with actuator_lag replays the
//    commands (DiagInput::cmd_*, or the body_velocity odometry) instead of the
//    wheels. The state starts at the command `lag_lead_in_s` before a window.
//  * odometry_bias b_v, b_w: the odometry read the body velocities + (b_v,
//    b_w) through its own nominal model (physics-effects.md; the simulator
//    offsets the wheel rates by the nominal inverse kinematics of (b_v, b_w),
//    or adds them to v_cmd, w_cmd), i.e. each nominal rim speed reads
//    b_v -+ b_w*D/2 too (D nominal, the OdoSeries' wheel_base_m; - left,
//    + right). So over an interval the nominal travel as recorded, d_rec
//    (after time_offset's read or actuator_lag's replay, which both act on
//    the recorded values; a constant offset commutes with both), becomes
//    d = d_rec - (b_v -+ b_w*D/2)*h before every other wheel effect. The
//    inverse of the simulator: the true body velocities are the odometry's
//    minus the bias (a robot at rest whose odometry creeps).
//  * Per wheel (left shown; right alike), with h = t_{k+1} - t_k and nominal
//    travel d:
//      R-scale   q  = radius_error.scale_l * (1 + (radius_step.scale_l - 1)*f),
//                     f = fraction of the interval at or after radius_step.t;
//      rim speed u  = q*d/h;   speed_radius: travel q*d*(1 + c*u^2);
//      longitudinal_slip: s = min(0.5, k*|du/dt|), du/dt = q*(1 + 3*c*u^2)*a,
//                     a = the nominal rim acceleration of the interval, a
//                     local quadratic fit of S over +-accel_half_window_s
//                     (differencing consecutive rim speeds would amplify the
//                     encoder quantisation into |du/dt|);
//      slip_zone: factor (1 - s_l) when the pose at the interval's start is in
//                     the box (tested on the current estimate's value);
//      ground travel g = q*d*(1 + c*u^2)*(1 - s)*(1 - s_zone).
//  * Body: ds = (g_r + g_l)/2, dtheta = (g_r - g_l)/(D*wheel_base_error.scale),
//    lateral_skid dy = -k*(ds/h)*(dtheta/h)*h. The pose then follows the arc
//    update (exact for velocities constant over the interval), see advance().
//  * gyro_bias, gyro_scale act on the gyro only (corrected_gyro_rate).
//
// Parameters travel as one flat vector: every parameter of every active effect,
// effects in the table order of odotune/sim/effects.h and parameters in each
// effect's order (param_layout() names them "effect.param"). radius_step.t and
// the slip_zone box enter as fixed numbers (their value is read, they are not
// differentiated); gyro parameters do not enter dead reckoning at all.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include <ceres/jet.h>

#include <odotune/core/planar_motion.h>
#include <odotune/diagnose/diag_input.h>

namespace odotune::diagnose {

// An effect, numbered as in sim::effect_table() (the spec's order); its name
// is effect_name(), read from the table (tests check that the two orders agree).
enum class Effect : int {
  radius_error,
  wheel_base_error,
  radius_step,
  speed_radius,
  lateral_skid,
  longitudinal_slip,
  slip_zone,
  gyro_bias,
  gyro_scale,
  actuator_lag,
  time_offset,
  odometry_bias
};
inline constexpr int kNumEffects = 12;

std::string_view effect_name(Effect e);
// Throws std::invalid_argument naming valid effects for an unknown name.
Effect effect_from_name(std::string_view name);
// What e does, in words ("whenever the robot turns: heading change off by a
// constant ratio"): a finding's `conditions` when the residuals single out none
// (diagnosis.h).
std::string_view effect_description(Effect e);

// True when e at its no-op values is another model than e switched off:
// actuator_lag, whose presence replays the commands instead of the wheels
// (file comment), so that its no-op still changes the odometry source. The
// selection's the own-parameters rule compares such an effect with its own no-op, not only
// with its absence (select.h).
inline bool noop_differs_from_absence(Effect e) { return e == Effect::actuator_lag; }

// gyro_bias or gyro_scale: an effect of the gyro, not of the wheel odometry.
inline bool is_gyro_effect(Effect e) { return e == Effect::gyro_bias || e == Effect::gyro_scale; }

// Which effects are active and their parameter values.
class EffectSet {
 public:
  // Specs in the command-line form of odotune/sim/effects.h ("lateral_skid:k=0.03");
  // parameters not given take their no-op values. Throws std::invalid_argument.
  static EffectSet parse(const std::vector<std::string>& specs);

  bool on(Effect e) const { return !p_[static_cast<int>(e)].empty(); }
  bool empty() const;
  // Switches e on with its no-op values (no change when already on).
  EffectSet& enable(Effect e);
  EffectSet& disable(Effect e);
  // Throws std::invalid_argument if e is off, the name is unknown or the value
  // is outside the table's range (the no-op value is always accepted).
  EffectSet& set(Effect e, std::string_view param, double value);
  double get(Effect e, std::string_view param) const;
  // Parameters of e in the table's order (empty when off).
  const std::vector<double>& params(Effect e) const { return p_[static_cast<int>(e)]; }
  // "radius_error:scale_l=0.99,scale_r=1.01; lateral_skid:k=0.03" or "none".
  std::string to_string() const;

 private:
  std::array<std::vector<double>, kNumEffects> p_;
};

// One entry of the flat parameter vector.
struct ParamSlot {
  Effect effect;
  int index;            // position in the effect's table parameters
  std::string name;     // "effect.param", names verbatim from the spec
  double lower, upper;  // fitting bounds: the table's range (an exclusive minimum
                        // is moved up by 1e-6 of the range)
  double noop;          // the value that switches the parameter's effect off
  bool fitted;          // false for radius_step.t, the slip_zone box and gyro_*:
                        // held fixed by a dead-reckoning fit
};
std::vector<ParamSlot> param_layout(const EffectSet& set);
std::vector<double> pack(const EffectSet& set);
// `structure` with its parameters replaced by `values` (layout order), each
// range-checked like EffectSet::set.
EffectSet unpack(const EffectSet& structure, const std::vector<double>& values);

// Gyro rate corrected for gyro_bias and gyro_scale: the true yaw rate for a
// reading `gyro_radps` (the gyro reads s*w + b).
template <typename T>
T corrected_gyro_rate(const T& gyro_radps, const T& bias_radps, const T& scale) {
  return (gyro_radps - bias_radps) / scale;
}
double corrected_gyro_rate(const EffectSet& set, double gyro_radps);

struct ModelOptions {
  double accel_half_window_s = 0.1;  // half width of the rim-acceleration fit [s]
  double lag_lead_in_s = 5.0;        // actuator_lag state starts this long before a window [s]
  bool IsValid(std::string* why) const;
};

// Parameter-independent data of the model, built once per input and effect
// structure: the nominal rim travel per wheel at the odometry nodes.
struct OdoSeries {
  bool from_commands = false;              // commands replayed (body_velocity or actuator_lag)
  double wheel_base_m = 0.0;               // nominal D (1 m when a body_velocity track has none)
  std::vector<double> t_s;                 // node times (DiagInput::odo_t_s)
  std::vector<double> s_l_m, s_r_m;        // cumulative nominal rim travel at the nodes
  std::vector<double> u_l_mps, u_r_mps;    // nominal rim speed at the nodes
  std::vector<double> a_l_mps2, a_r_mps2;  // nominal rim acceleration per interval
};

template <typename T>
struct BodyStep {
  T ds, dy, dth;  // forward [m], lateral (+ left) [m], heading change [rad]
};
template <typename T>
struct Pose {
  T x, y, th;  // [m], [m], [rad]
};

inline double scalar(double v) { return v; }
template <typename T, int N>
double scalar(const ceres::Jet<T, N>& v) {
  return v.a;
}

// Arc update of `p` by one body step (exact for constant velocities).
template <typename T>
void advance(Pose<T>& p, const BodyStep<T>& s) {
  const T half = 0.5 * s.dth;
  core::arc_advance(&p.x, &p.y, &p.th, half, core::sinc(half), s.ds, s.dy, s.dth);
}

class EffectModel {
 public:
  // Throws std::invalid_argument when the input cannot carry the set (e.g.
  // actuator_lag on wheel odometry without commands) or options are invalid.
  EffectModel(const DiagInput& input, const EffectSet& structure, const ModelOptions& opt = {});

  const EffectSet& structure() const { return structure_; }
  const std::vector<ParamSlot>& layout() const { return layout_; }
  const OdoSeries& series() const { return series_; }
  const ModelOptions& options() const { return opt_; }
  std::size_t num_nodes() const { return series_.t_s.size(); }

  // Positions of each parameter in the flat vector (-1 when its effect is off).
  struct Index {
    int re_l = -1, re_r = -1, wb = -1, rs_t = -1, rs_l = -1, rs_r = -1, sr_c = -1, skid_k = -1, slip_k = -1,
        zx0 = -1, zx1 = -1, zy0 = -1, zy1 = -1, z_l = -1, z_r = -1, tau = -1, dt = -1, ob_v = -1, ob_w = -1;
  };
  const Index& index() const { return idx_; }

 private:
  EffectSet structure_;
  std::vector<ParamSlot> layout_;
  OdoSeries series_;
  ModelOptions opt_;
  Index idx_;
};

// Steps the model through consecutive intervals for one parameter vector.
// Usage: Stepper<T> s(model, params); s.start(k0); then step(k0), step(k0+1)...
template <typename T>
class Stepper {
 public:
  Stepper(const EffectModel& m, const T* params) : m_(m), d_(m.series()), i_(m.index()), p_(params) {}

  void start(std::size_t k0) {
    cursor_ = 0;
    if (i_.tau >= 0 && scalar(p_[i_.tau]) > 0.0) {
      std::size_t k = k0;
      const double t0 = d_.t_s[k0] - m_.options().lag_lead_in_s;
      while (k > 0 && d_.t_s[k - 1] >= t0) --k;
      cmd(k, cl_, cr_);
      yl_ = cl_;
      yr_ = cr_;
      for (; k < k0; ++k) lag_step(k);
    } else {
      read_travel(k0, sl_, sr_);
    }
  }

  // True body motion over interval k (node k -> k+1); `pose` is the estimate
  // at node k (used only by slip_zone's inside test).
  BodyStep<T> step(std::size_t k, const Pose<T>& pose) {
    const double h = d_.t_s[k + 1] - d_.t_s[k];
    T dl, dr;
    if (i_.tau >= 0 && scalar(p_[i_.tau]) > 0.0) {
      const T yl0 = yl_, yr0 = yr_;
      lag_step(k);
      dl = 0.5 * h * (yl0 + yl_);
      dr = 0.5 * h * (yr0 + yr_);
    } else {
      T sl1, sr1;
      read_travel(k + 1, sl1, sr1);
      dl = sl1 - sl_;
      dr = sr1 - sr_;
      sl_ = sl1;
      sr_ = sr1;
    }
    if (i_.ob_v >= 0) {  // odometry_bias: the recorded rim speeds read b_v -+ b_w*D/2 too
      const T half_turn = p_[i_.ob_w] * (0.5 * d_.wheel_base_m);
      dl = dl - (p_[i_.ob_v] - half_turn) * h;
      dr = dr - (p_[i_.ob_v] + half_turn) * h;
    }
    bool zone = false;
    if (i_.z_l >= 0) {
      const double x = scalar(pose.x), y = scalar(pose.y);
      zone = x >= scalar(p_[i_.zx0]) && x <= scalar(p_[i_.zx1]) && y >= scalar(p_[i_.zy0]) &&
             y <= scalar(p_[i_.zy1]);
    }
    const T gl = ground(dl, h, d_.a_l_mps2[k], k, i_.re_l, i_.rs_l, zone ? i_.z_l : -1);
    const T gr = ground(dr, h, d_.a_r_mps2[k], k, i_.re_r, i_.rs_r, zone ? i_.z_r : -1);
    BodyStep<T> s;
    s.ds = 0.5 * (gr + gl);
    s.dth = i_.wb >= 0 ? (gr - gl) / (d_.wheel_base_m * p_[i_.wb]) : (gr - gl) / d_.wheel_base_m;
    s.dy = i_.skid_k >= 0 ? -p_[i_.skid_k] * s.ds * s.dth / h : T(0.0);
    return s;
  }

 private:
  // Ground travel of one wheel over interval k from its nominal travel d.
  T ground(const T& d, double h, double a_nom, std::size_t k, int re, int rs, int zone) const {
    T q = re >= 0 ? p_[re] : T(1.0);
    if (rs >= 0) {
      const double ts = scalar(p_[i_.rs_t]), t0 = d_.t_s[k], t1 = d_.t_s[k + 1];
      const double f = ts <= t0 ? 1.0 : ts >= t1 ? 0.0 : (t1 - ts) / (t1 - t0);
      if (f > 0.0) q = q * (1.0 + (p_[rs] - 1.0) * f);
    }
    T g = q * d;
    T grow = T(0.0);  // c*u^2
    if (i_.sr_c >= 0) {
      const T u = g / h;
      grow = p_[i_.sr_c] * u * u;
      g = g * (1.0 + grow);
    }
    if (i_.slip_k >= 0) {
      T dudt = q * (1.0 + 3.0 * grow) * a_nom;
      if (scalar(dudt) < 0.0) dudt = -dudt;
      T s = p_[i_.slip_k] * dudt;
      if (scalar(s) > 0.5) s = T(0.5);
      g = g * (1.0 - s);
    }
    if (zone >= 0) g = g * (1.0 - p_[zone]);
    return g;
  }

  // Commanded nominal rim speeds at node k (+ dt).
  void cmd(std::size_t k, T& cl, T& cr) {
    if (i_.dt < 0) {
      cl = T(d_.u_l_mps[k]);
      cr = T(d_.u_r_mps[k]);
      return;
    }
    const T tq = d_.t_s[k] + p_[i_.dt];
    const std::size_t n = d_.t_s.size();
    if (scalar(tq) <= d_.t_s.front() || scalar(tq) >= d_.t_s.back()) {
      const std::size_t e = scalar(tq) <= d_.t_s.front() ? 0 : n - 1;
      cl = T(d_.u_l_mps[e]);
      cr = T(d_.u_r_mps[e]);
      return;
    }
    const std::size_t j = cell(scalar(tq));
    const T f = (tq - d_.t_s[j]) / (d_.t_s[j + 1] - d_.t_s[j]);
    cl = d_.u_l_mps[j] + f * (d_.u_l_mps[j + 1] - d_.u_l_mps[j]);
    cr = d_.u_r_mps[j] + f * (d_.u_r_mps[j + 1] - d_.u_r_mps[j]);
  }

  // Advances the lag state over interval k (commands at nodes k and k+1).
  void lag_step(std::size_t k) {
    using std::exp;
    const double h = d_.t_s[k + 1] - d_.t_s[k];
    const T& tau = p_[i_.tau];
    T cl1, cr1;
    cmd(k + 1, cl1, cr1);
    const T e = exp(-h / tau);
    const T ramp = 1.0 - tau * (1.0 - e) / h;
    yl_ = e * yl_ + (1.0 - e) * cl_ + (cl1 - cl_) * ramp;
    yr_ = e * yr_ + (1.0 - e) * cr_ + (cr1 - cr_) * ramp;
    cl_ = cl1;
    cr_ = cr1;
  }

  // Cumulative nominal rim travel as true at node k: S(t_k + dt).
  void read_travel(std::size_t k, T& sl, T& sr) {
    if (i_.dt < 0) {
      sl = T(d_.s_l_m[k]);
      sr = T(d_.s_r_m[k]);
      return;
    }
    const T tq = d_.t_s[k] + p_[i_.dt];
    const std::size_t n = d_.t_s.size();
    if (scalar(tq) <= d_.t_s.front() || scalar(tq) >= d_.t_s.back()) {
      const std::size_t e = scalar(tq) <= d_.t_s.front() ? 0 : n - 1;
      sl = T(d_.s_l_m[e]);
      sr = T(d_.s_r_m[e]);
      return;
    }
    const std::size_t j = cell(scalar(tq));
    const double hh = d_.t_s[j + 1] - d_.t_s[j];
    const T s = (tq - d_.t_s[j]) / hh;
    const T s2 = s * s, s3 = s2 * s;
    const T h00 = 2.0 * s3 - 3.0 * s2 + 1.0, h10 = s3 - 2.0 * s2 + s;
    const T h01 = -2.0 * s3 + 3.0 * s2, h11 = s3 - s2;
    sl = h00 * d_.s_l_m[j] + h10 * (hh * d_.u_l_mps[j]) + h01 * d_.s_l_m[j + 1] +
         h11 * (hh * d_.u_l_mps[j + 1]);
    sr = h00 * d_.s_r_m[j] + h10 * (hh * d_.u_r_mps[j]) + h01 * d_.s_r_m[j + 1] +
         h11 * (hh * d_.u_r_mps[j + 1]);
  }

  // j with t_j <= tq < t_{j+1} (tq strictly inside the span); a cursor makes
  // consecutive, increasing queries O(1), a binary search handles jumps.
  std::size_t cell(double tq) {
    const auto& t = d_.t_s;
    if (cursor_ + 1 < t.size() && t[cursor_] <= tq) {
      if (tq < t[cursor_ + 1]) return cursor_;
      if (cursor_ + 2 < t.size() && tq < t[cursor_ + 2]) return ++cursor_;
    }
    const auto it = std::upper_bound(t.begin(), t.end(), tq);
    cursor_ = static_cast<std::size_t>(it - t.begin()) - 1;
    if (cursor_ + 1 >= t.size()) cursor_ = t.size() - 2;
    return cursor_;
  }

  const EffectModel& m_;
  const OdoSeries& d_;
  const EffectModel::Index& i_;
  const T* p_;
  std::size_t cursor_ = 0;
  T sl_{}, sr_{};                // travel read at the current node
  T yl_{}, yr_{}, cl_{}, cr_{};  // lag states and commands at the current node
};

}  // namespace odotune::diagnose
