// Random slip-episode layouts for a drive: training material for the slip
// detector (odotune/learned/slip_detector.h). One drive with ten hand-placed
// episodes teaches a 651-weight detector those ten episodes; a few drives
// with episodes of random kind, wheel, strength, length and place teach it
// slip (tests/learned/test_learned_odometry.cpp measures the difference
// on held-out drives). Fariña et al. (Sensors 2023, 23, 961, §4.1) likewise
// provoke slip many times, on either wheel, with worn tyres and with a hand.
//
// Episodes are placed only where the drive moves: each one lies wholly
// inside a stretch whose commanded |v| is at least `min_speed_m_s`
// (MotionProfile, the plan the simulator follows), so that a spin or a hold
// changes what the wheel does. Deterministic: the same profile, seed and
// options give the same list (draws are counter_uniform01 of the seed).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <odotune/sim/motion_profile.h>
#include <odotune/sim/scenario.h>

namespace odotune::sim {

struct RandomSlipOptions {
  double first_s = 6.0;                               // no episode starts before [s]
  double end_margin_s = 3.0;                          // none ends within this of the drive's end [s]
  double min_duration_s = 2.0, max_duration_s = 5.0;  // episode length, ramps included [s]
  double min_gap_s = 4.0, max_gap_s = 10.0;           // grip between episodes [s]
  double min_strength = 0.3, max_strength = 0.8;      // s, within (0, 0.9]
  double min_speed_m_s = 0.3;                         // |v| commanded throughout an episode
  // Hold brake [N*m] = hold_brake_per_s_nm * s + hold_brake_offset_nm, so
  // that a hold raises the motor power (simulator.h, "Slip episodes"; the
  // hand-placed episodes of scenarios/wheelchair_slip.yaml follow ~40 s − 6).
  double hold_brake_per_s_nm = 40.0, hold_brake_offset_nm = -6.0;
  // Ramp [s] = 0.2 + ramp_per_strength_s * max(0, s − 0.5): strong spins
  // lose grip over a few tenths of a second (scenarios/wheelchair_slip.yaml).
  double ramp_per_strength_s = 0.6;
  bool IsValid(std::string* why) const;
};

// Episodes for a drive following `profile`, alternating wheels at random,
// spin or hold at random, in time order, none overlapping (validate_slip_
// episodes holds). Throws std::invalid_argument for invalid options (one line
// naming the field). A drive too short or too slow for any episode gets none.
std::vector<SlipEpisode> random_slip_episodes(const MotionProfile& profile, std::uint64_t seed,
                                              const RandomSlipOptions& options = {});

}  // namespace odotune::sim
