// The random cases of the diagnosis benchmark (`odotune study diagnosis`;
// method in docs/diagnosis/benchmark.md): what case i of a
// run with seed S draws, and the track it simulates (odotune/sim/simulator.h),
// shaped to one of the reference shapes of docs/diagnosis-design.md ("Any
// reference").
//
// Case i draws everything from its own seed case_seed(S, i) (a SplitMix64
// hash of S and i, odotune/core/counter_rng.h), so a case is reproducible alone and
// the same for any thread count or case count. What it draws (uniform unless
// said; "log" = log-uniform):
//  * robot: a size z in [0, 1] sets the wheel radius 0.03-0.20 m (log), the
//    wheel base 4-8 radii (within 0.18-0.8 m), the drive's cruise speed
//    0.3-1.5 m/s and geometry 1-3 m (each +-20 %); 1 in 4 robots has unequal
//    nominal radii (up to +-1 %); encoder resolution one of 360..16384 counts
//    per revolution; acceleration limits 0.3-1 m/s^2 and 1-3 rad/s^2;
//  * drive: a lap of diagnosis_drives.h repeated for 60*U(min_minutes,
//    max_minutes) s, from a random start pose;
//  * odometry: ticks (1/2), wheel rates omega_l/r without ticks (1/5) or
//    commands v_cmd/w_cmd only (3/10), at 10-200 Hz; wheel odometry records
//    the commands alongside in half of the cases;
//  * gyro in 3/4 of the cases, 20-200 Hz, sigma 1-10 mrad/s (log);
//  * reference, one shape of five (1/5 each): gt_full (ground truth at
//    10-100 Hz, sigma 2-30 mm and 2-20 mrad, log), gt_gaps (the same with 1-4
//    gaps removing 15-40 % of the drive, none in its first 5 s), start_fixes
//    (ground truth only at the first row: a surveyed start; then fixes),
//    fixes (position fixes at 0.5-5 Hz, sigma 10-100 mm, log), fixes_irregular
//    (fixes kept from a 10 Hz stream at gaps of the mean period times
//    exp(U(-1.2, 1.2)));
//  * effects: none (null_share), one (1 - null_share - two_share) or two
//    distinct ones (two_share) of the effects the case can have: gyro_bias and
//    gyro_scale need a gyro, actuator_lag needs command odometry (with wheel
//    odometry the encoders measure the lagged wheels, so a lag is invisible
//    to dead reckoning); the others always. Sizes log-uniform from "barely
//    detectable" to "large" (effect_sizes in diagnosis_cases.cpp lists each
//    range); radius_step.t in 30-80 % of the drive; a slip_zone box around a
//    random point of the lap where the robot drives at least 0.3 of its cruise
//    speed, 0.6-1.5 g along the path and 0.3-1 g across it (so the drive
//    crosses it on every lap).
// Power and external-velocity sensors are off. The simulator's seed is the
// case seed.
//
// Multi-recording cases (a share multi_share of the cases, decided from a
// stream of the case seed of its own, so the single-recording draws above are
// the same whatever multi_share): 2, 3 or 4 recordings (1/3 each) of the
// case's ONE robot (its nominal geometry, odometry kind, sensor set, reference
// shape and true effects, with the same parameters), the last one held out
// (the last two of four). Recording k (1-based) draws from its own seed
// recording_seed(case seed, k): its own lap of the same family scale
// (diagnosis_drives.h), start pose and length 60*U(min_minutes, max_minutes) s,
// its own gaps (gt_gaps), its own simulator seed, and
//  * its true geometry: each wheel radius times 1 + N(0, 1e-4), the wheel base
//    times 1 + N(0, 3e-4) (half and under a third of the smallest radius_error
//    and wheel_base_error departures drawn, 2e-4 and 1e-3, and averaged over
//    the fit recordings: recording-to-recording variation far below
//    detectability); its track states the nominal geometry;
//  * its noise: the reference (ground-truth and fix) and gyro sigmas times
//    exp(U(-0.3, 0.3)) (the encoders have no noise beyond their counts).
// slip_zone and radius_step are never drawn for them: a box in world
// coordinates is not crossed by other drives, and a step time is a time of
// one recording.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <odotune/diagnose/effect_model.h>
#include <odotune/sim/scenario.h>
#include <odotune/tracks/track.h>

namespace odotune::studies {

enum class BenchOdometry { ticks, wheel_rates, commands };
enum class BenchReference { gt_full, gt_gaps, start_fixes, fixes, fixes_irregular };
std::string_view to_string(BenchOdometry o);
std::string_view to_string(BenchReference r);

struct CaseDrawOptions {
  double min_minutes = 1.0, max_minutes = 10.0;  // drive length, 0.2..60 min, min <= max
  double null_share = 1.0 / 3.0;                 // share of cases with no effect
  double two_share = 1.0 / 3.0;                  // share with two effects (the rest: one)
  double max_rate_hz = 200.0;                    // caps odometry, gyro and ground-truth rates (>= 10)
  double multi_share = 0.25;                     // share of multi-recording cases, [0, 1]

  // True when usable; otherwise *why names the first bad value.
  bool IsValid(std::string* why) const;
};

// A simulated effect with every parameter of physics-effects.md, table order.
struct TrueEffect {
  diagnose::Effect effect = diagnose::Effect::radius_error;
  std::vector<std::pair<std::string, double>> params;
  double param(std::string_view name) const;  // NaN when absent
  std::string_view name() const { return diagnose::effect_name(effect); }
  std::string spec() const;  // "lateral_skid:k=0.021" (odotune/sim/effects.h form)
};

// One recording of a multi-recording case (file comment).
struct CaseRecording {
  std::uint64_t seed = 0;  // recording_seed(case seed, k): everything below derives from it
  std::string drive;       // drive family (diagnosis_drives.h)
  double duration_s = 0.0;
  double radius_factor_l = 1.0, radius_factor_r = 1.0, base_factor = 1.0;  // true / nominal geometry
  double noise_factor = 1.0;                                               // reference and gyro sigmas
  bool heldout = false;                                                    // proven on, not fitted on
  std::vector<std::pair<double, double>> gt_gaps_s;                        // gt_gaps: [t0, t1) removed
  // What is simulated: the case's scenario with this recording's motion,
  // seed, true geometry and noise.
  sim::Scenario scenario;
};

struct DiagnosisCase {
  int index = 0;
  std::uint64_t seed = 0;  // case_seed(S, index): everything below derives from it
  std::string robot;       // "R 0.0625/0.0625 m, D 0.36 m, 2400 cpr"
  std::string drive;       // drive family (diagnosis_drives.h)
  double speed_m_s = 0.0, geometry_m = 0.0;
  double duration_s = 0.0;  // asked motion length (the profile lasts a little longer)
  BenchOdometry odometry = BenchOdometry::ticks;
  bool commands_alongside = false;  // wheel odometry with v_cmd/w_cmd recorded too
  double odo_rate_hz = 0.0;
  double gyro_rate_hz = 0.0, gyro_sigma_rad_s = 0.0;  // rate 0: no gyro
  BenchReference reference = BenchReference::gt_full;
  // Ground truth (gt_full, gt_gaps; start_fixes: the noise of its one pose).
  double gt_rate_hz = 0.0, gt_sigma_m = 0.0, gt_sigma_rad = 0.0;
  // Position fixes (start_fixes, fixes; fixes_irregular: the mean rate).
  double fix_rate_hz = 0.0, fix_sigma_m = 0.0;
  std::vector<std::pair<double, double>> gt_gaps_s;  // gt_gaps: [t0, t1) removed
  std::vector<TrueEffect> effects;                   // 0, 1 or 2
  // The simulation: its ground truth is always on (the true path, for
  // grading); make_case_track removes what the reference shape does not keep.
  sim::Scenario scenario;
  // Multi-recording case: its recordings, fit recordings first (file
  // comment); then `scenario` holds the nominal robot, sensors and effects,
  // drive and duration_s describe the recordings together, and each
  // recording's scenario is what is simulated. Empty: a single-recording case.
  std::vector<CaseRecording> recordings;

  bool multi() const { return !recordings.empty(); }
  int heldout_recordings() const;    // multi-recording cases: 1 or 2; else 0
  std::string effects_text() const;  // "; "-separated specs, or "none"
};

// Seed of case `index` of a run with seed `seed`.
std::uint64_t case_seed(std::uint64_t seed, int index);
// Seed of recording k (1-based) of a multi-recording case with seed `case_seed`.
std::uint64_t recording_seed(std::uint64_t case_seed, int k);

// Case `index` drawn from `seed` = case_seed(S, index) (file comment). Throws
// std::invalid_argument for invalid options.
DiagnosisCase draw_case(std::uint64_t seed, int index, const CaseDrawOptions& options);

struct CaseTrack {
  tracks::Track track;  // what the diagnosis sees
  // The true path (the simulation's ground truth, thinned to about 10 Hz),
  // for grading a slip_zone box.
  std::vector<double> path_t_s, path_x_m, path_y_m;
};

// Simulates the case and shapes its reference (file comment): ground truth
// removed, thinned or cut, fixes kept at irregular times, ticks dropped for
// wheel-rate odometry, rows left empty dropped; metadata bench.* records the
// case. Throws std::invalid_argument if the simulator rejects the scenario,
// or for a multi-recording case.
CaseTrack make_case_track(const DiagnosisCase& c);
// Recording k (0-based) of a multi-recording case, simulated and shaped as
// make_case_track does; the track states the nominal geometry (the case's
// scenario.robot), bench.recording its number (1-based) and whether it is
// held out. Throws std::invalid_argument for k out of range.
CaseTrack make_recording_track(const DiagnosisCase& c, std::size_t k);

// `track` without its ground-truth columns (rows left empty dropped, sim.gt_*
// metadata removed): what a known-start track's fixes give alone.
tracks::Track without_ground_truth(const tracks::Track& track);

}  // namespace odotune::studies
