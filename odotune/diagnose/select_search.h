// Internals of the model search of select.h, shared by select.cpp (the
// search's driver and the final model), select_search.cpp (the rules and
// the forward step) and select_moves.cpp (the swap to radius_error, swaps,
// pairs and the backward pass). Not part of the module's interface: nothing
// outside diagnose/ includes it. The rules (size, paired test, BIC, own parameters, materiality) are select.h's.
#pragma once

#include <chrono>
#include <initializer_list>
#include <limits>
#include <string>
#include <vector>

#include <odotune/core/non_finite.h>
#include <odotune/core/stopwatch.h>
#include <odotune/diagnose/cross_validate.h>
#include <odotune/diagnose/select.h>

namespace odotune::diagnose::select_detail {

using Clock = std::chrono::steady_clock;
using core::kNaN;
using core::kInf;

// The look-alikes of commanded velocities (diagnosis-design.md "Model selection", "Look-alikes"): each
// makes the motion trail the command.
inline constexpr Effect kLagLookAlikes[] = {Effect::time_offset, Effect::actuator_lag,
                                            Effect::longitudinal_slip};

using core::seconds_since;
// s with e switched on (its no-op values when it was off).
EffectSet with_effect(const EffectSet& s, Effect e);

// The materiality rule: the held-out error (position [m], heading [rad]) one evaluation
// removes from another's (removed()).
struct Removed {
  double pos_m = 0.0, heading_rad = 0.0;  // materiality.h removed_error_m of each
};
Removed removed(CrossValidator& cv, const SetEval& ref, const SetEval& alt);
// "" when material (the materiality rule), else why not.
std::string immaterial(const Removed& r, double floor_m, double floor_rad);
// "" when `p` passes the size, paired-test, BIC and materiality rules, else why not (delta_bic < 0 asked
// unless it is negative already; floor_m 0 = materiality not asked).
std::string verdict(const PairedComparison& p, double delta_bic, const SelectOptions& o,
                    const Removed& gain = {}, double floor_m = 0.0, double floor_rad = 0.0);
// Copy an evaluation's or a comparison's figures into a record.
void fill(SearchRecord& r, const SetEval& e);
void fill(SearchRecord& r, const PairedComparison& p);

// State of the search.
struct Search {
  CrossValidator& cv;
  const SelectOptions& o;
  Selection& sel;
  EffectSet s;                 // selected structure (no-op fitted values, discrete set)
  std::vector<Effect> chosen;  // in the order accepted
  SetEval cur_cv, cur_full;    // of s
  double step_t = kNaN;        // last radius_step.t found
  double floor_m = 0.0;        // materiality floor (the materiality rule) [m]
  double floor_rad = 0.0;      // its heading part [rad] (0 without a reference heading)
  bool heading = false;        // the reference has a heading
  // Look-alikes that predict as well as the chosen effects (look_alike_step).
  std::vector<Effect> look_alikes;
};

// The selection rules (select.h: size, paired test, BIC, own parameters, materiality) of a candidate set against the current set (select_search.cpp).
std::string judge(Search& z, const EffectSet& st, const SetEval& cv, std::initializer_list<Effect> added,
                  SearchRecord& rec, SetEval& full);
// The phases of the search (select.h): each true when it changed the set.
bool forward_step(Search& z, int step, const std::vector<Effect>& cands);
void prefer_radius_error(Search& z, int step);
bool swap_step(Search& z, int step, const std::vector<Effect>& cands);
bool pair_step(Search& z, int step, const std::vector<Effect>& cands);
bool backward_round(Search& z, int round);
bool look_alike_step(Search& z, int step);

}  // namespace odotune::diagnose::select_detail
