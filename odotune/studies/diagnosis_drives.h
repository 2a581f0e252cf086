// Random drives of the diagnosis benchmark (`odotune study diagnosis`,
// docs/diagnosis/benchmark.md): a closed lap of motion segments
// (odotune/sim/scenario.h) drawn from one of three families and repeated until the
// drive lasts long enough, and the commanded path of a motion (for placing a
// slip_zone box where the drive passes and for grading a found box).
//
// Every lap holds what the effects of ../shared/specs/physics-effects.md need
// to be told apart (docs/diagnosis-design.md, concealed suite): a stop at its
// start (gyro_bias, odometry_bias), straights at two or more speeds
// (speed_radius vs radius_error), accelerations and braking at every segment
// change (longitudinal_slip, time_offset, actuator_lag) and turns, both ways
// in the rectangle and figure-eight families (lateral_skid, wheel_base_error,
// gyro_scale). Families, with lengths in units of the geometry g and speeds
// in units of the cruise speed u:
//   rectangle: four sides of 1.5g-4g at 0.4u-1.2u each, left corners of
//     radius 0.3g-1g; each side may carry a lane change (arcs of radius g,
//     -theta then +theta, 15-40 deg), a stop of 1-3 s, a spin (+360 deg, or
//     +180 then -180 deg) or a short reversal (0.5g back, 0.5g forward);
//   oval: two straights of 2g-5g (at different speeds) joined by left
//     half-circles of radius 0.5g-1.5g, one straight with a lane change and a
//     stop;
//   figure8: a left circle and a right circle of radius 0.6g-1.5g (each
//     closes on itself, so the lap does), at different speeds, a stop and a
//     straight out-and-back (reversal) at the crossing point.
// A lap may be mirrored (every turn reversed), so drives with mostly right
// turns occur as well. Laps close only ideally; a robot under effects drifts,
// as it would.
//
// Draws come from CaseRng (odotune/core/counter_rng.h keyed by the case seed and a
// stream), so a drive depends on its seed only.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <odotune/sim/scenario.h>

namespace odotune::studies {

// Seeded uniform draws: the k-th draw of (seed, stream) is
// counter_uniform01(seed, k, 0, 0, stream), so a sequence depends on its seed
// and stream only, never on threads or on other cases.
class CaseRng {
 public:
  CaseRng(std::uint64_t seed, std::uint64_t stream) : seed_(seed), stream_(stream) {}
  double uniform();                          // [0, 1)
  double uniform(double lo, double hi);      // [lo, hi)
  double log_uniform(double lo, double hi);  // log-uniform in [lo, hi), 0 < lo <= hi
  int index(int n);                          // 0..n-1, n >= 1
  bool chance(double p);                     // true with probability p
  double sign();                             // -1 or +1
  template <class T>
  const T& pick(const std::vector<T>& v) {  // one element, v non-empty
    return v[static_cast<std::size_t>(index(static_cast<int>(v.size())))];
  }

 private:
  std::uint64_t seed_, stream_, k_ = 0;
};

// The robot-dependent scale of a drive.
struct DriveScale {
  double geometry_m = 1.0;        // g: lengths of the lap
  double speed_m_s = 0.5;         // u: cruise speed
  double spin_rate_deg_s = 90.0;  // rate of spins in place
};

struct Drive {
  std::string family;  // "rectangle", "oval" or "figure8", "+mirrored" when mirrored
  std::vector<sim::Segment> lap;
};

// One lap of a random family (file comment).
Drive draw_drive(CaseRng& rng, const DriveScale& scale);

// Segments: `lap` repeated (whole segments, a partial last lap allowed) until
// the motion under `motion`'s limits lasts at least duration_s, then 1 s at
// rest. Throws std::invalid_argument when the lap is empty or more than
// 100000 segments would be needed.
std::vector<sim::Segment> repeat_lap(const std::vector<sim::Segment>& lap, const sim::MotionParams& motion,
                                     double duration_s);

// The commanded path of `motion` (its commands integrated from the start
// pose by the arc update, as the nominal robot would drive them), sampled
// every step_s from 0 to the end of the motion.
struct PathSamples {
  std::vector<double> t_s, x_m, y_m, theta_rad;
};
PathSamples commanded_path(const sim::MotionParams& motion, double step_s);

}  // namespace odotune::studies
