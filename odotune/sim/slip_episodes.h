// Slip episodes (SlipEpisode in scenario.h): validation, the strength
// profile in time, and the text form written to a track's metadata as
//
//     sim.slip_episodes: spin:wheel=left,t0_s=40,t1_s=44,s=0.6,ramp_s=0.2; hold:wheel=right,t0_s=70,t1_s=73,s=0.5,ramp_s=0.2,brake_nm=6
//
// ("; "-separated, in the scenario's order; brake_nm only for hold; numbers in
// shortest round-trip form, so the text parses back to the same doubles). The
// simulator writes the key only when the scenario has episodes, so tracks
// without any stay byte-identical to those of earlier versions; "none" is
// accepted as "no episodes" too. With slip_strength()/slipping() a study
// labels the slip time of a simulated track without re-simulating it.
//
// The physics (what spin and hold do to the wheels, the motor power) is in
// simulator.h, "Slip episodes".
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include <odotune/sim/scenario.h>
#include <odotune/tracks/track.h>

namespace odotune::sim {

// Bound checked by validate_slip_episodes (no unbounded work per step).
inline constexpr std::size_t kMaxSlipEpisodes = 10'000;

// "spin"/"hold", "left"/"right".
std::string_view kind_name(SlipEpisode::Kind kind);
std::string_view wheel_name(SlipEpisode::Wheel wheel);

// Checks one episode's fields (scenario.h's ranges). On failure `field` is the
// field's name ("kind", "wheel", "t0_s", "t1_s", "s", "ramp_s", "brake_nm")
// and `why` says e.g. "s = 1.2; expected a strength in (0, 0.9]" (without the
// episode's index; validate_slip_episodes adds it).
bool check_slip_episode(const SlipEpisode& episode, std::string* field, std::string* why);

// Checks every episode and that episodes on the same wheel do not overlap.
// `why`: one line, e.g. "slip_episodes[2]: s = 1.2; expected a strength in
// (0, 0.9]" or "slip_episodes[3] overlaps slip_episodes[1] (line 12) on the
// left wheel: ..." (indices 1-based, in list order).
bool validate_slip_episodes(const std::vector<SlipEpisode>& episodes, std::string* why);

// Strength of one episode at time t_s (scenario.h's ramp profile), in [0, s];
// exactly 0 outside (t0_s, t1_s).
double episode_strength(const SlipEpisode& episode, double t_s);

// Strength of the episode acting on `wheel` at t_s (0 if none; the largest if
// an invalid list overlaps), whatever its kind.
double slip_strength(const std::vector<SlipEpisode>& episodes, double t_s, SlipEpisode::Wheel wheel);
// True when some episode has strength > 0 at t_s, on either wheel.
bool slipping(const std::vector<SlipEpisode>& episodes, double t_s);

// The metadata text above; "none" for an empty list.
std::string format_slip_episodes(const std::vector<SlipEpisode>& episodes);
// Parses that text ("none" or empty: no episodes). Each part is
// KIND:wheel=W,t0_s=..,t1_s=..,s=..[,ramp_s=..][,brake_nm=..] (ramp_s default
// 0.2, brake_nm default 0 and hold only), then validated. Throws
// std::invalid_argument with one line naming the part, the key and what was
// expected. Parsed episodes have line = 0.
std::vector<SlipEpisode> parse_slip_episodes(std::string_view text);
// The episodes of a simulated track (its sim.slip_episodes); empty when the
// key is absent or "none". Throws std::invalid_argument ("sim.slip_episodes:
// ...") on bad text.
std::vector<SlipEpisode> slip_episodes_from_metadata(const tracks::TrackMeta& meta);

// The episodes by wheel and start time, for the simulator's per-step look-up
// (a binary search instead of a scan of the whole list at every 1 ms step).
// Built from a valid list (validate_slip_episodes), at most one episode per
// wheel acts at any time.
class SlipSchedule {
 public:
  struct Active {
    const SlipEpisode* episode = nullptr;  // nullptr: no episode on this wheel now
    double strength = 0.0;                 // episode_strength at the queried time
  };

  explicit SlipSchedule(const std::vector<SlipEpisode>& episodes);
  Active at(double t_s, SlipEpisode::Wheel wheel) const;
  bool empty() const { return by_wheel_[0].empty() && by_wheel_[1].empty(); }

 private:
  std::array<std::vector<SlipEpisode>, 2> by_wheel_;  // [left, right], each sorted by t0_s
};

}  // namespace odotune::sim
