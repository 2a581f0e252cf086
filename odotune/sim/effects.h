// The vocabulary of physics effects (../shared/specs/physics-effects.md):
// effect and parameter names verbatim from the spec, with units, meanings,
// valid ranges and defaults; validation; and the command-line form
//
//     NAME[:PARAM=VALUE[,PARAM=VALUE]...]
//     e.g. "lateral_skid:k=0.02", "radius_error:scale_l=0.995,scale_r=1.004"
//
// which is also how sim.effects lists the active effects in a track's
// metadata ("; "-separated, or "none").
//
// All errors are one line naming the bad effect/parameter/value and what was
// expected (std::invalid_argument, or a bool + message for the check_* calls).
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <odotune/sim/scenario.h>

namespace odotune::sim {

struct EffectParamInfo {
  std::string_view name;  // verbatim from the spec
  std::string_view unit;  // "s", "s^2/m^2", "m", "1" (dimensionless), ...
  std::string_view meaning;
  double min;  // valid range [min, max] ...
  double max;
  bool min_exclusive;    // ... or (min, max] when true
  bool required;         // must be given when the effect is switched on
  double default_value;  // used when not required and not given (the no-op value)
};

struct EffectInfo {
  std::string_view name;  // verbatim from the spec
  std::string_view meaning;
  std::vector<EffectParamInfo> params;  // in the spec's order
};

// The 12 effects, in the spec's order.
const std::vector<EffectInfo>& effect_table();
// nullptr when unknown.
const EffectInfo* find_effect(std::string_view name);
const EffectParamInfo* find_param(const EffectInfo& effect, std::string_view param);
// "radius_error, wheel_base_error, ..." and "scale_l, scale_r".
std::string effect_names();
std::string param_names(const EffectInfo& effect);
// The closest of `candidates` to `word` if it is a plausible misspelling
// (edit distance <= max(1, |word|/3)), else "".
std::string closest_name(std::string_view word, const std::vector<std::string_view>& candidates);

// Checks one value against the table (finite, inside the range). On failure
// `why` says e.g. "radius_error.scale_l = 3 is out of range [0.5, 1.5]".
bool check_param(const EffectInfo& effect, const EffectParamInfo& param, double value, std::string* why);

// A partial setting of one effect: the parameters the user gave.
struct EffectSpec {
  std::string name;
  std::vector<std::pair<std::string, double>> values;
};

// Parses the command-line form. Checks names, numbers and ranges (not that
// required parameters are present: that is apply_effect's job, since a spec
// may complete an effect the scenario file already switched on).
// Throws std::invalid_argument, e.g.
//   "effect 'lateral_skd': unknown effect; did you mean 'lateral_skid'? valid: radius_error, ..."
EffectSpec parse_effect_spec(std::string_view text);

// Switches the effect on (parameters not given take their defaults) or, if it
// is already on, overrides just the given parameters. Throws
// std::invalid_argument on an unknown name/parameter, an out-of-range value,
// a missing required parameter or an inconsistent combination (slip_zone with
// x0 >= x1).
void apply_effect(Effects& effects, const EffectSpec& spec);
void remove_effect(Effects& effects, std::string_view name);

// The active effects with all their parameters, in table order.
std::vector<EffectSpec> active_effects(const Effects& effects);
// "radius_error:scale_l=0.997,scale_r=1.003; lateral_skid:k=0.02" or "none".
// Numbers in shortest round-trip form, so each part parses back exactly.
std::string format_effects(const Effects& effects);
std::string format_effect(const EffectSpec& spec);

// Ranges of every active parameter and cross-parameter rules.
bool validate_effects(const Effects& effects, std::string* why);

}  // namespace odotune::sim
