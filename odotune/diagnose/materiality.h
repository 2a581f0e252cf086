// When a finding matters (docs/diagnosis-design.md, "Findings that matter"):
// a finding is reported only when it is significant (select.h's
// paired tests and BIC) AND material: the held-out position error it removes
// must pass a floor tied to the reference's own noise and to the nominal
// model's error,
//
//   floor_m = max(min_gain_sigmas * ref_sigma_m,
//                 min_gain_share * nominal_heldout_pos_rmse_m),
//   removed_m = sqrt(before_heldout_pos_rmse_m^2 - after_heldout_pos_rmse_m^2),
//   material  <=>  removed_m >= floor_m.
//
// removed_m is the RMS error the finding removes: the reference's own noise
// adds to both RMSEs in quadrature (before^2 = e^2 + n^2, after^2 = n^2 for a
// perfect model), so their plain difference shrinks a real gain whenever the
// noise is comparable (e = n: before - after = 0.41 n, removed = n); the
// quadrature difference measures e itself, whatever the noise.
// ref_sigma_m is the standard deviation of one reference position sample
// (DiagInput::ref_sigma_m: stated by the metadata or estimated, >= 1 mm);
// nominal_heldout_pos_rmse_m the nominal model's held-out position RMSE of the
// windowed replay. Why both terms: a gain below one reference sigma cannot be
// seen in any single position the user compares against (on tens of thousands
// of samples it can still be significant: a 0.6 ms lag, a 2 ms time offset
// beside a 0.13 s lag); a gain below a few percent of what the nominal model
// gets wrong changes nothing a user acts on, even when the reference is
// precise. Timing effects far below the sampling period are not exempt and get
// no other rule: they are findings exactly when they pass this floor.
//
// The selection (select.h the materiality rule) applies the same floor to heading too
// when the reference has one: a wheel effect is material when its removed
// heading error passes max(min_gain_sigmas * ref_sigma_rad, min_gain_share
// * nominal heading RMSE), whatever its position gain.
//
// The same floor decides, from the truth, whether a simulated effect is
// detectable at all (the random benchmark, studies/): the true model's
// held-out gain over the nominal one against this floor.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

#include <odotune/diagnose/option_rules.h>

namespace odotune::diagnose {

struct MaterialityOptions {
  // Floor part: reference position sigmas. Half: an error below half of one
  // reference sample's noise shows in no plot or comparison a user makes
  // against that reference.
  double min_gain_sigmas = 0.5;
  // Floor part: share of the nominal held-out position RMSE (removed in
  // quadrature): what a user acts on is a visible part of what the nominal
  // model gets wrong.
  double min_gain_share = 0.05;
  // Both chosen on the development seeds 1001-1003 of `odotune study
  // diagnosis`, the unit tests and the documented examples, never on the
  // docs run's seed.

  bool IsValid(std::string* why) const {
    return check_option_rules({{is_non_negative(min_gain_sigmas), "min_gain_sigmas", min_gain_sigmas, ">= 0"},
                               {is_fraction(min_gain_share), "min_gain_share", min_gain_share, "in [0, 1]"}},
                              why);
  }
};

// The floor [m] (file comment); NaN inputs count as 0.
inline double materiality_floor_m(double ref_sigma_m, double nominal_heldout_pos_rmse_m,
                                  const MaterialityOptions& o = {}) {
  const double s = std::isfinite(ref_sigma_m) ? ref_sigma_m : 0.0;
  const double n = std::isfinite(nominal_heldout_pos_rmse_m) ? nominal_heldout_pos_rmse_m : 0.0;
  return std::max(o.min_gain_sigmas * s, o.min_gain_share * n);
}

// sqrt(before^2 - after^2) [m], 0 when after >= before; NaN for NaN input.
inline double removed_error_m(double before_pos_rmse_m, double after_pos_rmse_m) {
  const double d = before_pos_rmse_m * before_pos_rmse_m - after_pos_rmse_m * after_pos_rmse_m;
  return std::isfinite(d) ? std::sqrt(std::max(d, 0.0)) : std::nan("");
}

// True when removed_error_m passes floor_m (file comment); false for NaN.
inline bool is_material(double before_pos_rmse_m, double after_pos_rmse_m, double floor_m) {
  const double removed = removed_error_m(before_pos_rmse_m, after_pos_rmse_m);
  return std::isfinite(removed) && removed > 0.0 && removed >= floor_m;
}

}  // namespace odotune::diagnose
