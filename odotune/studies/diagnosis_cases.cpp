#include <odotune/studies/diagnosis_cases.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/counter_rng.h>
#include <odotune/core/why.h>
#include <odotune/sim/effects.h>
#include <odotune/sim/motion_profile.h>
#include <odotune/sim/simulator.h>
#include <odotune/studies/diagnosis_drives.h>

namespace odotune::studies {

namespace {

using diagnose::Effect;

// Counter-RNG streams (odotune/core/counter_rng.h); any fixed, distinct values do.
constexpr std::uint64_t kCaseStream = 0x6469616763617365ULL;   // "diagcase"
constexpr std::uint64_t kDrawStream = 0x64726177ULL;           // "draw"
constexpr std::uint64_t kFixStream = 0x6669786573ULL;          // "fixes"
constexpr std::uint64_t kMultiStream = 0x6d756c7469ULL;        // "multi"
constexpr std::uint64_t kRecordingStream = 0x7265636f7264ULL;  // "record"

// Recording-to-recording variation of the true geometry (relative sigmas)
// and of the noise (log-uniform factor bound) of multi-recording cases
// (diagnosis_cases.h).
constexpr double kRadiusJitter = 1e-4, kBaseJitter = 3e-4, kNoiseLogSpread = 0.3;

template <class T>
std::vector<T> at_most(const std::vector<T>& values, double cap) {
  std::vector<T> out;
  for (const T& v : values)
    if (v <= cap) out.push_back(v);
  return out.empty() ? std::vector<T>{values.front()} : out;
}

TrueEffect make_effect(Effect effect, const std::vector<std::pair<std::string, double>>& given) {
  const sim::EffectInfo* info = sim::find_effect(diagnose::effect_name(effect));
  if (info == nullptr)
    throw std::invalid_argument(fmt::format("unknown effect {}", diagnose::effect_name(effect)));
  TrueEffect e;
  e.effect = effect;
  for (const sim::EffectParamInfo& p : info->params) {
    double v = p.default_value;
    for (const auto& [n, value] : given)
      if (n == p.name) v = value;
    e.params.emplace_back(std::string(p.name), v);
  }
  return e;
}

// A pair of radius scales: both wheels off by the same departure (2/5),
// one wheel only (1/5), or independently (2/5), each departure a random
// sign times log-uniform [lo, hi).
std::pair<double, double> scale_pair(CaseRng& rng, double lo, double hi) {
  const double a = rng.sign() * rng.log_uniform(lo, hi);
  const double kind = rng.uniform();
  if (kind < 0.4) return {1.0 + a, 1.0 + a};
  if (kind < 0.6) return rng.chance(0.5) ? std::pair{1.0 + a, 1.0} : std::pair{1.0, 1.0 + a};
  return {1.0 + a, 1.0 + rng.sign() * rng.log_uniform(lo, hi)};
}

// Axis-aligned box around a point of the first lap where the robot drives
// at >= 0.3 of its cruise speed: 0.6-1.5 g along the path, 0.3-1 g across.
std::vector<std::pair<std::string, double>> zone_box(CaseRng& rng, const DiagnosisCase& c, double lap_s) {
  sim::MotionParams first = c.scenario.motion;
  const PathSamples p = commanded_path(first, 0.1);
  std::vector<std::size_t> moving;
  for (std::size_t i = 5; i + 5 < p.t_s.size() && p.t_s[i] < lap_s; ++i) {
    const double v = std::hypot(p.x_m[i + 5] - p.x_m[i - 5], p.y_m[i + 5] - p.y_m[i - 5]) / 1.0;
    if (v >= 0.3 * c.speed_m_s) moving.push_back(i);
  }
  if (moving.empty()) throw std::invalid_argument("slip_zone: the lap never moves at speed");
  const std::size_t i = moving[static_cast<std::size_t>(rng.index(static_cast<int>(moving.size())))];
  const double along = rng.uniform(0.6, 1.5) * c.geometry_m, across = rng.uniform(0.3, 1.0) * c.geometry_m;
  const double co = std::abs(std::cos(p.theta_rad[i])), si = std::abs(std::sin(p.theta_rad[i]));
  const double hx = 0.5 * (along * co + across * si), hy = 0.5 * (along * si + across * co);
  return {{"x0", p.x_m[i] - hx}, {"x1", p.x_m[i] + hx}, {"y0", p.y_m[i] - hy}, {"y1", p.y_m[i] + hy}};
}

// The effect `effect` with its size drawn (ranges: "barely detectable" to
// "large"; docs/diagnosis/benchmark.md lists them).
TrueEffect draw_effect(CaseRng& rng, Effect effect, const DiagnosisCase& c, double lap_s) {
  const double u = c.speed_m_s, g = c.geometry_m;
  const double rim_max = 1.2 * u + c.scenario.robot.wheel_base_m;  // rough upper rim speed [m/s]
  if (effect == Effect::radius_error) {
    const auto [l, r] = scale_pair(rng, 2e-4, 2e-2);
    return make_effect(effect, {{"scale_l", l}, {"scale_r", r}});
  }
  if (effect == Effect::wheel_base_error)
    return make_effect(effect, {{"scale", 1.0 + rng.sign() * rng.log_uniform(1e-3, 5e-2)}});
  if (effect == Effect::radius_step) {
    const double t = rng.uniform(0.3, 0.8) * c.duration_s;
    const auto [l, r] = scale_pair(rng, 1e-3, 3e-2);
    return make_effect(effect, {{"t", std::round(t * 10.0) / 10.0}, {"scale_l", l}, {"scale_r", r}});
  }
  if (effect == Effect::speed_radius) {
    const double cc = rng.sign() * rng.log_uniform(3e-4, 3e-2) / (rim_max * rim_max);
    return make_effect(effect, {{"c", std::clamp(cc, -0.1, 0.1)}});
  }
  if (effect == Effect::lateral_skid) return make_effect(effect, {{"k", rng.log_uniform(0.005, 0.2)}});
  if (effect == Effect::longitudinal_slip) {
    const double k = rng.log_uniform(2e-3, 0.1) / c.scenario.motion.max_accel_m_s2;
    return make_effect(effect, {{"k", std::min(k, 10.0)}});
  }
  if (effect == Effect::slip_zone) {
    auto box = zone_box(rng, c, lap_s);
    const double s = rng.log_uniform(0.01, 0.3);
    const double s_r = rng.chance(1.0 / 3.0) ? s : std::min(0.9, s * rng.uniform(0.7, 1.3));
    box.emplace_back("s_l", s);
    box.emplace_back("s_r", s_r);
    return make_effect(effect, box);
  }
  if (effect == Effect::gyro_bias)
    return make_effect(effect, {{"b", rng.sign() * rng.log_uniform(1e-4, 1e-2)}});
  if (effect == Effect::gyro_scale)
    return make_effect(effect, {{"s", 1.0 + rng.sign() * rng.log_uniform(3e-4, 3e-2)}});
  if (effect == Effect::actuator_lag) return make_effect(effect, {{"tau", rng.log_uniform(0.01, 0.5)}});
  if (effect == Effect::time_offset)
    return make_effect(effect, {{"dt", rng.sign() * rng.log_uniform(0.002, 0.3)}});
  if (effect == Effect::odometry_bias) {
    const double kind = rng.uniform();
    const double b_v = kind < 2.0 / 3.0 ? rng.sign() * rng.log_uniform(5e-4, 5e-2) * u : 0.0;
    const double b_w = kind >= 1.0 / 3.0 ? rng.sign() * rng.log_uniform(5e-4, 5e-2) * u / g : 0.0;
    return make_effect(effect, {{"b_v", b_v}, {"b_w", b_w}});
  }
  throw std::invalid_argument(fmt::format("draw_effect: no draw for effect {}", diagnose::effect_name(effect)));
}

// Effects the case can have (file comment), in table order; a
// multi-recording case has neither slip_zone nor radius_step.
std::vector<Effect> eligible_effects(const DiagnosisCase& c, bool multi) {
  std::vector<Effect> out;
  for (int i = 0; i < diagnose::kNumEffects; ++i) {
    const auto e = static_cast<Effect>(i);
    if (diagnose::is_gyro_effect(e) && c.gyro_rate_hz <= 0.0) continue;
    if (e == Effect::actuator_lag && c.odometry != BenchOdometry::commands) continue;
    if (multi && (e == Effect::slip_zone || e == Effect::radius_step)) continue;
    out.push_back(e);
  }
  return out;
}

// 1-4 gaps removing 15-40 % of a drive of duration_s, none in its first 5 s.
std::vector<std::pair<double, double>> draw_gaps(CaseRng& rng, double duration_s) {
  std::vector<std::pair<double, double>> out;
  const int gaps = 1 + rng.index(4);
  const double total = rng.uniform(0.15, 0.40) * duration_s;
  const double span = duration_s - 5.0;
  for (int k = 0; k < gaps; ++k) {
    // Gap k starts in the k-th of `gaps` equal parts after the first 5 s.
    const double len = total / gaps, part = span / gaps;
    const double t0 = 5.0 + k * part + rng.uniform(0.0, std::max(0.0, part - len));
    out.emplace_back(t0, t0 + std::min(len, part));
  }
  return out;
}

// A standard normal draw (Box-Muller).
double normal(CaseRng& rng) {
  const double u = rng.uniform(), v = rng.uniform();
  return std::sqrt(-2.0 * std::log(1.0 - u)) * std::cos(2.0 * std::numbers::pi * v);
}

// Recording k (1-based) of `count` of multi-recording case c (header
// comment): c's scenario with its own drive, seed, true geometry and noise.
CaseRecording draw_recording(const DiagnosisCase& c, const DriveScale& scale, int k, int count,
                             const CaseDrawOptions& o) {
  CaseRecording rec;
  rec.seed = recording_seed(c.seed, k);
  rec.heldout = k > count - (count >= 4 ? 2 : 1);
  CaseRng rng(rec.seed, kDrawStream);
  sim::Scenario& sc = rec.scenario;
  sc = c.scenario;
  sc.name = fmt::format("bench_case_{}_r{}", c.index, k);
  sc.seed = rec.seed;
  sim::MotionParams& m = sc.motion;
  m.start_x_m = rng.uniform(-5.0, 5.0);
  m.start_y_m = rng.uniform(-5.0, 5.0);
  m.start_theta_rad = rng.uniform(-3.14159, 3.14159);
  const Drive drive = draw_drive(rng, scale);
  rec.drive = drive.family;
  rec.duration_s = 60.0 * rng.uniform(o.min_minutes, o.max_minutes);
  m.segments = repeat_lap(drive.lap, m, rec.duration_s);
  rec.radius_factor_l = 1.0 + kRadiusJitter * normal(rng);
  rec.radius_factor_r = 1.0 + kRadiusJitter * normal(rng);
  rec.base_factor = 1.0 + kBaseJitter * normal(rng);
  sc.robot.wheel_radius_left_m *= rec.radius_factor_l;
  sc.robot.wheel_radius_right_m *= rec.radius_factor_r;
  sc.robot.wheel_base_m *= rec.base_factor;
  rec.noise_factor = std::exp(rng.uniform(-kNoiseLogSpread, kNoiseLogSpread));
  sim::SensorParams& s = sc.sensors;
  for (double* sigma :
       {&s.gyro.sigma_rad_s, &s.ground_truth.sigma_m, &s.ground_truth.sigma_rad, &s.aps.sigma_m})
    *sigma *= rec.noise_factor;
  if (c.reference == BenchReference::gt_gaps) rec.gt_gaps_s = draw_gaps(rng, rec.duration_s);
  std::string why;
  if (!sim::validate_scenario(sc, &why))
    throw std::invalid_argument(fmt::format("diagnosis benchmark case {} recording {}: {}", c.index, k, why));
  return rec;
}

void set_sensors(DiagnosisCase& c) {
  sim::SensorParams& s = c.scenario.sensors;
  const bool wheels = c.odometry != BenchOdometry::commands;
  s.encoders.enabled = wheels;
  s.encoders.rate_hz = c.odo_rate_hz;
  s.encoders.omega = c.odometry == BenchOdometry::wheel_rates;
  s.commands.enabled = !wheels || c.commands_alongside;
  s.commands.rate_hz = c.odo_rate_hz;
  s.gyro.enabled = c.gyro_rate_hz > 0.0;
  s.gyro.rate_hz = c.gyro_rate_hz > 0.0 ? c.gyro_rate_hz : 100.0;
  s.gyro.sigma_rad_s = c.gyro_sigma_rad_s;
  s.power.enabled = false;
  s.ext_velocity.enabled = false;
  const bool gt_ref = c.reference == BenchReference::gt_full || c.reference == BenchReference::gt_gaps;
  // Ground truth always on: the reference, or the true path (noise-free,
  // 10 Hz) that make_case_track removes; a surveyed start keeps its noise.
  s.ground_truth.enabled = true;
  s.ground_truth.rate_hz = gt_ref ? c.gt_rate_hz : 10.0;
  s.ground_truth.sigma_m = c.gt_sigma_m;  // 0 unless gt_ref or start_fixes
  s.ground_truth.sigma_rad = c.gt_sigma_rad;
  s.aps.enabled = !gt_ref;
  s.aps.rate_hz = c.reference == BenchReference::fixes_irregular ? 10.0 : (gt_ref ? 1.0 : c.fix_rate_hz);
  s.aps.sigma_m = gt_ref ? 0.06 : c.fix_sigma_m;
}

// Draws the `count` recordings of multi-recording case c; its drive and
// duration_s then describe them together.
void add_recordings(DiagnosisCase& c, const DriveScale& scale, int count, const CaseDrawOptions& o) {
  c.drive.clear();
  c.duration_s = 0.0;
  for (int k = 1; k <= count; ++k) {
    c.recordings.push_back(draw_recording(c, scale, k, count, o));
    c.drive += (k > 1 ? " + " : "") + c.recordings.back().drive;
    c.duration_s += c.recordings.back().duration_s;
  }
}

}  // namespace

std::string_view to_string(BenchOdometry o) {
  switch (o) {
    case BenchOdometry::ticks: return "ticks";
    case BenchOdometry::wheel_rates: return "wheel_rates";
    case BenchOdometry::commands: return "commands";
  }
  return "";
}

std::string_view to_string(BenchReference r) {
  switch (r) {
    case BenchReference::gt_full: return "gt_full";
    case BenchReference::gt_gaps: return "gt_gaps";
    case BenchReference::start_fixes: return "start_fixes";
    case BenchReference::fixes: return "fixes";
    case BenchReference::fixes_irregular: return "fixes_irregular";
  }
  return "";
}

bool CaseDrawOptions::IsValid(std::string* why) const {
  if (!(min_minutes >= 0.2 && min_minutes <= 60.0))
    return core::invalid(why, fmt::format("min_minutes = {} must be in [0.2, 60]", min_minutes));
  if (!(max_minutes >= min_minutes && max_minutes <= 60.0))
    return core::invalid(why, fmt::format("max_minutes = {} must be in [min_minutes = {}, 60]", max_minutes,
                                          min_minutes));
  if (!(null_share >= 0.0 && null_share <= 1.0))
    return core::invalid(why, fmt::format("null_share = {} must be in [0, 1]", null_share));
  if (!(two_share >= 0.0 && two_share <= 1.0 - null_share))
    return core::invalid(why, fmt::format("two_share = {} must be in [0, 1 - null_share = {}]", two_share,
                                          1.0 - null_share));
  if (!(max_rate_hz >= 10.0 && max_rate_hz <= 1000.0))
    return core::invalid(why, fmt::format("max_rate_hz = {} must be in [10, 1000]", max_rate_hz));
  if (!(multi_share >= 0.0 && multi_share <= 1.0))
    return core::invalid(why, fmt::format("multi_share = {} must be in [0, 1]", multi_share));
  return true;
}

double TrueEffect::param(std::string_view n) const {
  for (const auto& [key, v] : params)
    if (key == n) return v;
  return std::numeric_limits<double>::quiet_NaN();
}

std::string TrueEffect::spec() const {
  sim::EffectSpec s{std::string(name()), params};
  return sim::format_effect(s);
}

int DiagnosisCase::heldout_recordings() const {
  return static_cast<int>(std::count_if(recordings.begin(), recordings.end(),
                                        [](const CaseRecording& r) { return r.heldout; }));
}

std::string DiagnosisCase::effects_text() const {
  std::string out;
  for (const TrueEffect& e : effects) out += (out.empty() ? "" : "; ") + e.spec();
  return out.empty() ? "none" : out;
}

std::uint64_t case_seed(std::uint64_t seed, int index) {
  return core::counter_hash(seed, static_cast<std::uint64_t>(index), 0, 0, kCaseStream);
}

std::uint64_t recording_seed(std::uint64_t case_seed, int k) {
  return core::counter_hash(case_seed, static_cast<std::uint64_t>(k), 0, 0, kRecordingStream);
}

namespace {

// Robot: radii (one draw `z` of the robot's size, returned: the drive's scale
// grows with it), wheel base, encoder, and the motion's limits and start.
double draw_robot(CaseRng& rng, DiagnosisCase& c) {
  const double z = rng.uniform();
  sim::RobotParams& r = c.scenario.robot;
  r.wheel_radius_left_m = 0.03 * std::pow(0.20 / 0.03, z);
  r.wheel_radius_right_m = r.wheel_radius_left_m * (rng.chance(0.25) ? 1.0 + rng.uniform(-0.01, 0.01) : 1.0);
  r.wheel_base_m = std::clamp(r.wheel_radius_left_m * rng.uniform(4.0, 8.0), 0.18, 0.8);
  r.ticks_per_rev = rng.pick(std::vector<double>{360, 500, 1000, 1024, 1440, 2048, 2400, 4096, 8192, 16384});
  c.robot = fmt::format("R {:.4g}/{:.4g} m, D {:.3g} m, {:g} cpr", r.wheel_radius_left_m,
                        r.wheel_radius_right_m, r.wheel_base_m, r.ticks_per_rev);
  sim::MotionParams& m = c.scenario.motion;
  m.max_accel_m_s2 = rng.uniform(0.3, 1.0);
  m.max_angular_accel_rad_s2 = rng.uniform(1.0, 3.0);
  m.start_x_m = rng.uniform(-5.0, 5.0);
  m.start_y_m = rng.uniform(-5.0, 5.0);
  m.start_theta_rad = rng.uniform(-3.14159, 3.14159);
  return z;
}

// Drive: its scale (from the robot's size draw `z`), family and duration, the
// lap repeated over it; `lap_s` gets one lap's duration.
DriveScale draw_drive_of(CaseRng& rng, DiagnosisCase& c, double z, const CaseDrawOptions& o, double& lap_s) {
  sim::MotionParams& m = c.scenario.motion;
  DriveScale scale;
  scale.speed_m_s = 0.3 * std::pow(5.0, z) * rng.uniform(0.8, 1.2);
  scale.geometry_m = 1.0 * std::pow(3.0, z) * rng.uniform(0.8, 1.2);
  scale.spin_rate_deg_s = rng.uniform(60.0, 150.0);
  c.speed_m_s = scale.speed_m_s;
  c.geometry_m = scale.geometry_m;
  const Drive drive = draw_drive(rng, scale);
  c.drive = drive.family;
  c.duration_s = 60.0 * rng.uniform(o.min_minutes, o.max_minutes);
  m.segments = repeat_lap(drive.lap, m, c.duration_s);
  lap_s = [&] {
    sim::MotionParams one = m;
    one.segments = drive.lap;
    return sim::MotionProfile(one).duration_s();
  }();
  return scale;
}

// Sensors: the odometry's kind and rate, the gyro, the reference's shape,
// rates and noise; then the scenario's sensors from them.
void draw_sensors(CaseRng& rng, DiagnosisCase& c, const CaseDrawOptions& o) {
  const double kind = rng.uniform();
  c.odometry = kind < 0.5   ? BenchOdometry::ticks
               : kind < 0.7 ? BenchOdometry::wheel_rates
                            : BenchOdometry::commands;
  c.commands_alongside = c.odometry != BenchOdometry::commands && rng.chance(0.5);
  c.odo_rate_hz = rng.pick(at_most(std::vector<double>{10, 20, 25, 40, 50, 100, 200}, o.max_rate_hz));
  if (rng.chance(0.75)) {
    c.gyro_rate_hz = rng.pick(at_most(std::vector<double>{20, 50, 100, 200}, o.max_rate_hz));
    c.gyro_sigma_rad_s = rng.log_uniform(0.001, 0.01);
  }
  c.reference = static_cast<BenchReference>(rng.index(5));
  const bool gt_ref = c.reference == BenchReference::gt_full || c.reference == BenchReference::gt_gaps;
  if (gt_ref || c.reference == BenchReference::start_fixes) {
    c.gt_rate_hz = rng.pick(at_most(std::vector<double>{10, 20, 25, 50, 100}, o.max_rate_hz));
    c.gt_sigma_m = rng.log_uniform(0.002, 0.03);
    c.gt_sigma_rad = rng.log_uniform(0.002, 0.02);
  }
  if (!gt_ref) {
    c.fix_rate_hz = c.reference == BenchReference::fixes_irregular
                        ? rng.pick(std::vector<double>{0.5, 1, 2, 4})
                        : rng.pick(std::vector<double>{0.5, 1, 2, 4, 5});
    c.fix_sigma_m = rng.log_uniform(0.01, 0.1);
  }
  if (c.reference == BenchReference::gt_gaps) c.gt_gaps_s = draw_gaps(rng, c.duration_s);
  set_sensors(c);
}

// Effects: none, one or two of those eligible, in the effect table's order,
// applied to the scenario.
void draw_effects(CaseRng& rng, DiagnosisCase& c, bool multi, double lap_s, const CaseDrawOptions& o) {
  const double count_draw = rng.uniform();
  const int count = count_draw < o.null_share ? 0 : count_draw < o.null_share + o.two_share ? 2 : 1;
  std::vector<Effect> pool = eligible_effects(c, multi);
  for (int k = 0; k < count; ++k) {
    const std::size_t at = static_cast<std::size_t>(rng.index(static_cast<int>(pool.size())));
    const Effect effect = pool[at];
    pool.erase(pool.begin() + static_cast<std::ptrdiff_t>(at));
    c.effects.push_back(draw_effect(rng, effect, c, lap_s));
  }
  // Table order, as sim.effects and the diagnosis list them.
  std::sort(c.effects.begin(), c.effects.end(),
            [](const TrueEffect& a, const TrueEffect& b) { return a.effect < b.effect; });
  for (const TrueEffect& e : c.effects)
    sim::apply_effect(c.scenario.effects, sim::EffectSpec{std::string(e.name()), e.params});
}

}  // namespace

DiagnosisCase draw_case(std::uint64_t seed, int index, const CaseDrawOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument("diagnosis benchmark: " + why);
  CaseRng rng(seed, kDrawStream);
  DiagnosisCase c;
  c.index = index;
  c.seed = seed;
  c.scenario.name = fmt::format("bench_case_{}", index);
  c.scenario.seed = seed;
  const double z = draw_robot(rng, c);
  double lap_s = 0.0;
  const DriveScale scale = draw_drive_of(rng, c, z, o, lap_s);
  draw_sensors(rng, c, o);
  CaseRng multi_rng(seed, kMultiStream);  // its own stream: the draws above do not depend on multi_share
  const bool multi = multi_rng.uniform() < o.multi_share;
  draw_effects(rng, c, multi, lap_s, o);
  if (!sim::validate_scenario(c.scenario, &why))
    throw std::invalid_argument(fmt::format("diagnosis benchmark case {}: {}", index, why));
  if (multi) add_recordings(c, scale, 2 + multi_rng.index(3), o);
  return c;
}

namespace {

// Rows of `d` for which keep(i), columns without any sample left removed.
tracks::TrackData keep_rows(const tracks::TrackData& d, const std::vector<bool>& keep) {
  tracks::TrackData out;
  out.meta = d.meta;
  for (std::size_t i = 0; i < d.t.size(); ++i) {
    if (!keep[i]) continue;
    out.t.push_back(d.t[i]);
    for (int k = 0; k < tracks::kNumCols; ++k)
      if (!d.cols[k].empty()) out.cols[k].push_back(d.cols[k][i]);
    if (!d.ticks_l.empty()) {
      out.ticks_l.push_back(d.ticks_l[i]);
      out.ticks_r.push_back(d.ticks_r[i]);
    }
  }
  for (auto& col : out.cols)
    if (std::all_of(col.begin(), col.end(), [](double v) { return std::isnan(v); })) col.clear();
  return out;
}

// Rows holding at least one sample.
std::vector<bool> non_empty_rows(const tracks::TrackData& d) {
  std::vector<bool> keep(d.t.size(), false);
  for (std::size_t i = 0; i < d.t.size(); ++i) {
    bool any = !d.ticks_l.empty() && d.ticks_l[i] != tracks::kNoTick;
    for (int k = 0; k < tracks::kNumCols && !any; ++k) any = !d.cols[k].empty() && !std::isnan(d.cols[k][i]);
    keep[i] = any;
  }
  return keep;
}

void erase_meta(tracks::TrackMeta& meta, std::string_view prefix) {
  std::erase_if(meta.extra, [&](const auto& kv) { return kv.first.rfind(prefix, 0) == 0; });
}

// The simulation of `sc` shaped to c's reference (make_case_track): `gaps`
// the ground-truth gaps, `seed` the seed of the irregular fixes' times.
CaseTrack shape_track(const DiagnosisCase& c, const sim::Scenario& sc,
                      const std::vector<std::pair<double, double>>& gaps, std::uint64_t seed) {
  tracks::TrackData d = sim::simulate(sc).data();
  const std::size_t n = d.t.size();
  std::vector<double> path_t, path_x, path_y;
  const auto& gx = d.col(tracks::Col::gt_x);
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isnan(gx[i]) && (path_t.empty() || d.t[i] >= path_t.back() + 0.1 - 1e-9)) {
      path_t.push_back(d.t[i]);
      path_x.push_back(gx[i]);
      path_y.push_back(d.col(tracks::Col::gt_y)[i]);
    }
  auto clear_gt_if = [&](auto&& pred) {
    for (std::size_t i = 0; i < n; ++i)
      if (pred(i))
        d.col(tracks::Col::gt_x)[i] = d.col(tracks::Col::gt_y)[i] = d.col(tracks::Col::gt_theta)[i] = std::nan(
            "");
  };
  switch (c.reference) {
    case BenchReference::gt_full: break;
    case BenchReference::gt_gaps:
      clear_gt_if([&](std::size_t i) {
        return std::any_of(gaps.begin(), gaps.end(),
                           [&](const auto& g) { return d.t[i] >= g.first && d.t[i] < g.second; });
      });
      break;
    case BenchReference::start_fixes: {
      bool first = true;
      clear_gt_if([&](std::size_t i) {
        if (std::isnan(gx[i])) return false;
        const bool clear = !first;
        first = false;
        return clear;
      });
      break;
    }
    case BenchReference::fixes:
    case BenchReference::fixes_irregular: clear_gt_if([](std::size_t) { return true; }); break;
  }
  if (c.reference == BenchReference::fixes_irregular) {
    // Gaps of P*exp(U(-1.2, 1.2)) divided by that factor's mean, sinh(1.2)/1.2,
    // so that the mean gap is P = 1/fix_rate_hz.
    CaseRng rng(seed, kFixStream);
    const double period = 1.0 / c.fix_rate_hz, mean_factor = std::sinh(1.2) / 1.2;
    auto& ax = d.col(tracks::Col::aps_x);
    auto& ay = d.col(tracks::Col::aps_y);
    double next = -1.0;
    for (std::size_t i = 0; i < n; ++i) {
      if (std::isnan(ax[i])) continue;
      if (next < 0.0) next = d.t[i] + period * std::exp(rng.uniform(-1.2, 1.2)) / mean_factor;
      if (d.t[i] + 1e-9 >= next) {
        next = d.t[i] + period * std::exp(rng.uniform(-1.2, 1.2)) / mean_factor;
      } else {
        ax[i] = ay[i] = std::nan("");
      }
    }
  }
  if (c.odometry == BenchOdometry::wheel_rates) {
    d.ticks_l.clear();
    d.ticks_r.clear();
  }
  tracks::TrackData shaped = keep_rows(d, non_empty_rows(d));
  tracks::TrackMeta& meta = shaped.meta;
  if (shaped.col(tracks::Col::gt_x).empty()) erase_meta(meta, "sim.gt_");
  if (shaped.col(tracks::Col::aps_x).empty()) erase_meta(meta, "sim.aps_");
  if (c.reference == BenchReference::fixes_irregular) {
    erase_meta(meta, "sim.aps_rate_hz");
    meta.extra.emplace_back("bench.fix_mean_rate_hz", fmt::format("{:g}", c.fix_rate_hz));
  }
  meta.extra.emplace_back("bench.case", std::to_string(c.index));
  meta.extra.emplace_back("bench.case_seed", std::to_string(c.seed));
  meta.extra.emplace_back("bench.odometry", std::string(to_string(c.odometry)));
  meta.extra.emplace_back("bench.reference", std::string(to_string(c.reference)));
  return CaseTrack{tracks::Track(std::move(shaped)), std::move(path_t), std::move(path_x), std::move(path_y)};
}

}  // namespace

CaseTrack make_case_track(const DiagnosisCase& c) {
  if (c.multi())
    throw std::invalid_argument(fmt::format("case {} is a multi-recording case: make_recording_track",
                                            c.index));
  CaseTrack ct = shape_track(c, c.scenario, c.gt_gaps_s, c.seed);
  tracks::TrackData d = ct.track.data();
  d.meta.extra.emplace_back("bench.drive", c.drive);
  ct.track = tracks::Track(std::move(d));
  return ct;
}

CaseTrack make_recording_track(const DiagnosisCase& c, std::size_t k) {
  if (k >= c.recordings.size())
    throw std::invalid_argument(fmt::format("case {} has {} recording(s), not a recording {}", c.index,
                                            c.recordings.size(), k + 1));
  const CaseRecording& rec = c.recordings[k];
  CaseTrack ct = shape_track(c, rec.scenario, rec.gt_gaps_s, rec.seed);
  tracks::TrackData d = ct.track.data();
  // The nominal geometry: the recording was simulated with its true one.
  const sim::RobotParams& nominal = c.scenario.robot;
  d.meta.wheel_radius_left_m = nominal.wheel_radius_left_m;
  d.meta.wheel_radius_right_m = nominal.wheel_radius_right_m;
  d.meta.wheel_base_m = nominal.wheel_base_m;
  d.meta.extra.emplace_back("bench.drive", rec.drive);
  d.meta.extra.emplace_back("bench.recording", std::to_string(k + 1));
  d.meta.extra.emplace_back("bench.recordings", std::to_string(c.recordings.size()));
  d.meta.extra.emplace_back("bench.heldout", rec.heldout ? "1" : "0");
  d.meta.extra.emplace_back("bench.recording_seed", std::to_string(rec.seed));
  ct.track = tracks::Track(std::move(d));
  return ct;
}

tracks::Track without_ground_truth(const tracks::Track& track) {
  tracks::TrackData d = track.data();
  for (tracks::Col c : {tracks::Col::gt_x, tracks::Col::gt_y, tracks::Col::gt_theta}) d.col(c).clear();
  tracks::TrackData out = keep_rows(d, non_empty_rows(d));
  erase_meta(out.meta, "sim.gt_");
  return tracks::Track(std::move(out));
}

}  // namespace odotune::studies
