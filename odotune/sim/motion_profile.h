// Commanded body velocities v_cmd(t) [m/s], w_cmd(t) [rad/s] from a list of
// motion segments (scenario.h) under acceleration limits, or from explicit
// velocity knots (end of this comment).
//
// How segments become a profile:
//  * Each segment has a cruise command (v_i, w_i): straight (+-speed, 0),
//    arc (speed, sign(angle)*speed/radius), spin (0, sign(angle)*rate),
//    stop (0, 0); and a nominal duration d_i = geometry / cruise
//    (|distance|/speed, |angle|*radius/speed, |angle|/rate).
//  * The robot starts and ends at rest. Between consecutive cruises (and from
//    / to rest) v and w change LINEARLY and TOGETHER over the transition time
//    T = max(|dv|/max_accel, |dw|/max_angular_accel), so |dv/dt| and |dw/dt|
//    never exceed the limits (a trapezoidal profile per segment).
//  * Each transition is centred on the nominal boundary between the two
//    segments. A linear ramp centred on a step has the same integral as the
//    step, so at the end of every transition the (signed) travelled distance
//    and the heading change equal EXACTLY those of the segments' geometry; the
//    path only rounds the corners (it cuts them by O(v*T) during the
//    transition). A transition between forward and reverse passes through 0.
//  * A stop keeps the robot at rest for its full duration_s: its slot is
//    lengthened by half of each adjoining transition.
//  * A moving segment too short to hold half of each adjoining transition
//    cannot reach its cruise: its cruise (v_i and w_i together, so the arc's
//    radius is kept) is lowered in 5 % steps until it fits; its geometry is
//    still met exactly. If no speed fits (never in practice), ProfileError.
//
// The result is piecewise linear in t and stored as knots.
//
// Explicit knots (a non-empty MotionParams::knots, e.g. the velocities along a
// recorded track) are used AS GIVEN: the profile is linear between them and
// holds the first / last knot's command outside [0, duration]. They are only
// checked: every value finite, the first t_s = 0, t_s strictly increasing
// (ProfileError naming the 1-based knot; its segment() is the 0-based knot
// index). The
// acceleration limits are NOT applied to knots (a recording may accelerate
// harder than a planner would; the limits must still be valid numbers and are
// written to the track's metadata). A MotionParams with both segments and
// knots is a ProfileError; plan() is empty for a knots profile.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include <odotune/sim/scenario.h>

namespace odotune::sim {

// A profile that cannot be built; `segment` is the 0-based index into
// MotionParams::segments, or into MotionParams::knots for a knots profile
// (or npos for the whole list).
class ProfileError : public std::invalid_argument {
 public:
  ProfileError(std::size_t segment, const std::string& what) : std::invalid_argument(what), segment_(segment) {}
  std::size_t segment() const { return segment_; }
  static constexpr std::size_t npos = static_cast<std::size_t>(-1);

 private:
  std::size_t segment_;
};

// Cruise command and geometry of one segment as described above; throws
// ProfileError for a non-finite or out-of-domain field (naming it).
struct Cruise {
  double v_m_s = 0.0;
  double w_rad_s = 0.0;
  double duration_s = 0.0;  // nominal duration at this cruise
};
Cruise segment_cruise(const Segment& s, std::size_t index);

struct Command {
  double v_m_s = 0.0;
  double w_rad_s = 0.0;
};

class MotionProfile {
 public:
  struct Knot {
    double t_s;
    double v_m_s;
    double w_rad_s;
  };
  // What became of segment i: its cruise after any lowering (speed_scale < 1
  // when lowered) and the nominal boundaries [begin_s, end_s] (transition
  // centres).
  struct Planned {
    double v_m_s, w_rad_s, speed_scale, begin_s, end_s;
  };

  // Throws ProfileError (see file comment). An empty segment list (and no
  // knots) gives a profile of zero duration.
  explicit MotionProfile(const MotionParams& motion);

  // Command at time t [s]; outside [0, duration_s()] the first / last knot's
  // command ((0, 0) for segments, which start and end at rest).
  Command at(double t_s) const;
  double duration_s() const { return knots_.empty() ? 0.0 : knots_.back().t_s; }
  const std::vector<Knot>& knots() const { return knots_; }
  const std::vector<Planned>& plan() const { return plan_; }

 private:
  std::vector<Knot> knots_;
  std::vector<Planned> plan_;
};

}  // namespace odotune::sim
