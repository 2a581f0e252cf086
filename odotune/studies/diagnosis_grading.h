// Grading one benchmark case (docs/diagnosis/benchmark.md,
// "Grading"): the diagnosis of the case's track against its truth and the
// truth's detectability (diagnosis_truth.h).
//
// Sets: E = the detectable true effects (expected), T = the true effects that
// are not detectable (tolerated: named or not, neither counts, and their
// parameters are not graded), F = the effects the diagnosis names
// (`unexplained` included). Category by |E|: `single` (1), `two` (2), and
// with |E| = 0 `null` (no effect simulated) or `undetectable` (effects
// simulated, none detectable). A two-effect case with one detectable effect
// is a `single` case graded on that effect.
//
// A case passes when
//  * F \ T = E: exactly the expected effects named, no other (an
//    `unexplained` finding is a wrong extra finding);
//  * every parameter of every expected effect is within its tolerance
//    (param_tolerance(); slip_zone's box by the path, below);
//  * held-out improved: Diagnosis::heldout.after < before when E holds a
//    wheel-odometry effect, and each expected gyro finding's own held-out
//    after < before.
// Null and undetectable cases pass when F \ T is empty. A refused track (the
// diagnosis threw) fails with the refusal's message.
//
// Parameter tolerances: ±25 % of the parameter's DEPARTURE from its no-op
// value, with these rules for parameters that can sit at their no-op value:
//  * radius_step.t: ±5 s of driving time; when the true t lies in a gap of
//    the reference (TruePath::ref_gaps_s), anywhere in that gap ±5 s: no
//    reference sample tells where in the gap the step happened; and the
//    time between the found t and the truth (or the gap) during which the
//    odometry stands still (TruePath::standstills_s) does not count: a
//    radius that changes while the wheels do not turn changes nothing until
//    they do, so no sample tells when in the standstill it changed;
//  * scale pairs (radius_error and radius_step scale_l/scale_r, slip_zone
//    s_l/s_r): 25 % of the pair's larger departure, so a wheel that is not
//    off (scale 1) must come out within that of 1;
//  * odometry_bias b_v, b_w: 25 % of the larger departure measured as a rim
//    speed, max(|b_v|, |b_w|*D/2) (D the nominal wheel base), i.e. b_v within
//    that, b_w within that divided by D/2;
//  * slip_zone box: its edges are reported (error against the truth) but not
//    graded one by one, since an edge the drive never crosses is not
//    determined by the data; the box is graded by the true path: of the
//    path samples inside the true box, at least 75 % must be inside the found
//    box, and the path samples inside the found box but outside the true one
//    must number at most 25 % of those inside the true box.
// A parameter's normalised error = (found - truth) / (tolerance / 0.25), so
// |normalised| <= 0.25 is within tolerance for every rule (radius_step.t:
// error / 20 s).
#pragma once

#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <odotune/diagnose/diagnosis.h>
#include <odotune/studies/diagnosis_truth.h>

namespace odotune::studies {

enum class CaseCategory { null_case, undetectable, single, two };
std::string_view to_string(CaseCategory c);  // "null", "undetectable", "single", "two"

struct ParamCheck {
  diagnose::Effect effect = diagnose::Effect::radius_error;
  std::string param;
  double truth = std::numeric_limits<double>::quiet_NaN();
  double found = std::numeric_limits<double>::quiet_NaN();
  double tolerance = std::numeric_limits<double>::quiet_NaN();   // absolute
  double normalised = std::numeric_limits<double>::quiet_NaN();  // (found - truth) / (tolerance / 0.25)
  bool graded = true;                                            // false: reported only (slip_zone edges)
  bool ok = false;
};

// The true path, for the slip_zone box rule (CaseTrack::path_*).
struct TruePath {
  std::vector<double> x_m, y_m;
  // Gaps of the track's reference [s] (reference_gaps below): radius_step.t
  // inside one is graded against the gap (header comment).
  std::vector<std::pair<double, double>> ref_gaps_s;
  // Standstills of the odometry [s] (odometry_standstills below): not
  // counted in radius_step.t's miss (header comment).
  std::vector<std::pair<double, double>> standstills_s;
};

// The intervals over which the odometry shows no motion: both wheel angles
// unchanged between consecutive samples, or body velocities v = w = 0 at
// both ends, as (first sample, last sample) of each run.
std::vector<std::pair<double, double>> odometry_standstills(const diagnose::DiagInput& in);

// |b - a| less the parts of [min, max] that lie in `standstills_s` [s].
double driving_time_between(double a, double b, const std::vector<std::pair<double, double>>& standstills_s);

// The gaps of a reference: consecutive sample times more than two median
// periods apart, as (last sample before, first sample after).
std::vector<std::pair<double, double>> reference_gaps(const std::vector<double>& ref_t_s);

struct CaseGrade {
  CaseCategory category = CaseCategory::null_case;
  bool pass = false;
  bool refused = false;
  std::vector<diagnose::Effect> expected, tolerated, missed;  // true effects
  std::vector<diagnose::FindingKind> found, extra;            // named by the diagnosis
  std::vector<ParamCheck> params;                             // expected effects only
  bool named_ok = false, params_ok = false, heldout_ok = false;
  double heldout_before_m = std::numeric_limits<double>::quiet_NaN();  // Diagnosis::heldout
  double heldout_after_m = std::numeric_limits<double>::quiet_NaN();
  std::string why;  // failure reasons ("missed X; named Y; X.p = ... out of ±...; refused: ...")
};

CaseCategory case_category(const std::vector<EffectTruth>& truth);

// Absolute tolerance of parameter `param` of true effect `e` (rules above;
// not for the slip_zone box edges). wheel_base_m: the nominal base.
double param_tolerance(const TrueEffect& e, std::string_view param, double wheel_base_m);

// Slip_zone box rule (above): share of the true box's path samples inside
// `found`, and the found box's extra samples over the true box's count.
struct BoxCoverage {
  double covered = 0.0, extra = 0.0;
  int samples = 0;  // path samples inside the true box
};
BoxCoverage box_coverage(const TrueEffect& truth, double x0, double x1, double y0, double y1,
                         const TruePath& path);

CaseGrade grade_case(const std::vector<EffectTruth>& truth, const diagnose::Diagnosis& d, double wheel_base_m,
                     const TruePath& path);
CaseGrade grade_refusal(const std::vector<EffectTruth>& truth, const std::string& message);

}  // namespace odotune::studies
