#include <odotune/studies/diagnosis_drives.h>

#include <cmath>
#include <stdexcept>

#include <odotune/core/counter_rng.h>
#include <odotune/sim/motion_profile.h>

namespace odotune::studies {

double CaseRng::uniform() { return core::counter_uniform01(seed_, k_++, 0, 0, stream_); }
double CaseRng::uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
double CaseRng::log_uniform(double lo, double hi) { return lo * std::exp(std::log(hi / lo) * uniform()); }
int CaseRng::index(int n) {
  const int i = static_cast<int>(uniform() * n);
  return i < n ? i : n - 1;
}
bool CaseRng::chance(double p) { return uniform() < p; }
double CaseRng::sign() { return chance(0.5) ? 1.0 : -1.0; }

namespace {

using K = sim::Segment::Kind;

sim::Segment straight(double d_m, double v_m_s) {
  sim::Segment s;
  s.kind = K::straight, s.distance_m = d_m, s.speed_m_s = v_m_s;
  return s;
}
sim::Segment arc(double r_m, double deg, double v_m_s) {
  sim::Segment s;
  s.kind = K::arc, s.radius_m = r_m, s.angle_deg = deg, s.speed_m_s = v_m_s;
  return s;
}
sim::Segment spin(double deg, double rate_deg_s) {
  sim::Segment s;
  s.kind = K::spin, s.angle_deg = deg, s.rate_deg_s = rate_deg_s;
  return s;
}
sim::Segment stop(double sec) {
  sim::Segment s;
  s.kind = K::stop, s.duration_s = sec;
  return s;
}

// A side of length len at speed v, split around one optional feature that
// ends where it starts and keeps the heading (lane changes shift sideways by
// a little; the side is shortened by the lane change's length).
void add_side(std::vector<sim::Segment>& lap, CaseRng& rng, const DriveScale& s, double len, double v) {
  const double g = s.geometry_m;
  const int feature = rng.index(5);  // 0 none, 1 lane change, 2 stop, 3 spin, 4 reversal
  const double first = len * rng.uniform(0.3, 0.6);
  lap.push_back(straight(first, v));
  switch (feature) {
    case 1: {
      const double th = rng.uniform(15.0, 40.0), dir = rng.sign();
      lap.push_back(arc(g, -dir * th, 0.8 * v));
      lap.push_back(arc(g, dir * th, 0.8 * v));
      break;
    }
    case 2: lap.push_back(stop(rng.uniform(1.0, 3.0))); break;
    case 3:
      if (rng.chance(0.5)) {
        lap.push_back(spin(360.0, s.spin_rate_deg_s));
      } else {
        lap.push_back(spin(180.0, s.spin_rate_deg_s));
        lap.push_back(spin(-180.0, s.spin_rate_deg_s));
      }
      break;
    case 4:
      lap.push_back(straight(-0.5 * g, 0.5 * s.speed_m_s));
      lap.push_back(straight(0.5 * g, 0.7 * s.speed_m_s));
      break;
    default: break;
  }
  lap.push_back(straight(len - first, v));
}

std::vector<sim::Segment> rectangle(CaseRng& rng, const DriveScale& s) {
  const double g = s.geometry_m, u = s.speed_m_s;
  std::vector<sim::Segment> lap = {stop(rng.uniform(1.0, 2.5))};
  // Two distinct speeds at least: one slow side, one fast side, two random.
  const double speeds[4] = {rng.uniform(0.4, 0.65) * u, rng.uniform(0.95, 1.2) * u, rng.uniform(0.4, 1.2) * u,
                            rng.uniform(0.4, 1.2) * u};
  const int first = rng.index(4);
  for (int side = 0; side < 4; ++side) {
    add_side(lap, rng, s, rng.uniform(1.5, 4.0) * g, speeds[(first + side) % 4]);
    lap.push_back(arc(rng.uniform(0.3, 1.0) * g, 90.0, rng.uniform(0.4, 0.8) * u));
  }
  return lap;
}

std::vector<sim::Segment> oval(CaseRng& rng, const DriveScale& s) {
  const double g = s.geometry_m, u = s.speed_m_s;
  const double len = rng.uniform(2.0, 5.0) * g, r = rng.uniform(0.5, 1.5) * g;
  std::vector<sim::Segment> lap = {stop(rng.uniform(1.0, 2.5))};
  const double fast = rng.uniform(0.9, 1.2) * u, slow = rng.uniform(0.35, 0.6) * u;
  const double th = rng.uniform(15.0, 40.0), dir = rng.sign();
  lap.push_back(straight(0.4 * len, fast));
  lap.push_back(arc(g, -dir * th, 0.8 * fast));
  lap.push_back(arc(g, dir * th, 0.8 * fast));
  lap.push_back(straight(0.6 * len, fast));
  lap.push_back(arc(r, 180.0, rng.uniform(0.5, 0.8) * u));
  lap.push_back(straight(0.5 * len, slow));
  lap.push_back(stop(rng.uniform(1.0, 3.0)));
  lap.push_back(straight(0.5 * len, slow));
  lap.push_back(arc(r, 180.0, rng.uniform(0.5, 0.8) * u));
  return lap;
}

std::vector<sim::Segment> figure8(CaseRng& rng, const DriveScale& s) {
  const double g = s.geometry_m, u = s.speed_m_s;
  std::vector<sim::Segment> lap = {stop(rng.uniform(1.0, 2.5))};
  lap.push_back(arc(rng.uniform(0.6, 1.5) * g, 360.0, rng.uniform(0.8, 1.2) * u));
  lap.push_back(stop(rng.uniform(0.5, 2.0)));
  lap.push_back(straight(rng.uniform(0.5, 1.5) * g, rng.uniform(0.5, 1.0) * u));
  lap.push_back(straight(-lap.back().distance_m, rng.uniform(0.4, 0.8) * u));
  lap.push_back(arc(rng.uniform(0.6, 1.5) * g, -360.0, rng.uniform(0.4, 0.7) * u));
  if (rng.chance(0.5)) lap.push_back(spin(rng.sign() * 360.0, s.spin_rate_deg_s));
  return lap;
}

}  // namespace

Drive draw_drive(CaseRng& rng, const DriveScale& scale) {
  Drive d;
  switch (rng.index(3)) {
    case 0: d.family = "rectangle", d.lap = rectangle(rng, scale); break;
    case 1: d.family = "oval", d.lap = oval(rng, scale); break;
    default: d.family = "figure8", d.lap = figure8(rng, scale); break;
  }
  if (rng.chance(0.3)) {
    d.family += "+mirrored";
    for (sim::Segment& seg : d.lap) seg.angle_deg = -seg.angle_deg;
  }
  return d;
}

std::vector<sim::Segment> repeat_lap(const std::vector<sim::Segment>& lap, const sim::MotionParams& motion,
                                     double duration_s) {
  if (lap.empty()) throw std::invalid_argument("repeat_lap: empty lap");
  sim::MotionParams probe = motion;
  probe.knots.clear();
  probe.segments.clear();
  // Whole laps first (one profile per lap count), then whole segments.
  const double lap_s = [&] {
    sim::MotionParams one = probe;
    one.segments = lap;
    return sim::MotionProfile(one).duration_s();
  }();
  const auto laps = static_cast<std::size_t>(std::max(0.0, std::floor(duration_s / lap_s) - 1.0));
  for (std::size_t l = 0; l < laps; ++l) probe.segments.insert(probe.segments.end(), lap.begin(), lap.end());
  for (std::size_t k = 0; k < 100000; ++k) {
    probe.segments.push_back(lap[k % lap.size()]);
    sim::MotionParams with_rest = probe;
    with_rest.segments.push_back(stop(1.0));
    if (sim::MotionProfile(with_rest).duration_s() >= duration_s) return with_rest.segments;
  }
  throw std::invalid_argument("repeat_lap: the lap is too short for the drive");
}

PathSamples commanded_path(const sim::MotionParams& motion, double step_s) {
  const sim::MotionProfile profile(motion);
  PathSamples p;
  double x = motion.start_x_m, y = motion.start_y_m, th = motion.start_theta_rad;
  const auto n = static_cast<std::size_t>(std::floor(profile.duration_s() / step_s)) + 1;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * step_s;
    p.t_s.push_back(t), p.x_m.push_back(x), p.y_m.push_back(y), p.theta_rad.push_back(th);
    // Midpoint command, arc update (exact for constant velocities). Not
    // odotune/core/planar_motion.h's arc_advance: the benchmark's cases were drawn
    // along this path, and that rounding moves their zones in the 16th digit.
    const sim::Command c = profile.at(t + 0.5 * step_s);
    const double dth = c.w_rad_s * step_s, half = 0.5 * dth;
    const double sc = std::abs(half) < 1e-6 ? 1.0 : std::sin(half) / half;
    x += sc * c.v_m_s * step_s * std::cos(th + half);
    y += sc * c.v_m_s * step_s * std::sin(th + half);
    th += dth;
  }
  return p;
}

}  // namespace odotune::studies
