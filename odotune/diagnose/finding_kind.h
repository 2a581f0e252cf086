// What a finding of a diagnosis names (../shared/specs/diagnosis-output.md,
// "effect"): an effect of physics-effects.md, or `unexplained` (growth the
// list does not explain, diagnosis.h). Its name is written and read in one
// place, to_string / finding_kind_from_name; everything else compares values.
#pragma once

#include <string_view>
#include <variant>

#include <odotune/diagnose/effect_model.h>

namespace odotune::diagnose {

// The kind of the `unexplained` finding.
struct Unexplained {
  bool operator==(const Unexplained&) const = default;
};

using FindingKind = std::variant<Effect, Unexplained>;

// effect_name(e), or the name of Unexplained (the spec's "unexplained").
std::string_view to_string(const FindingKind& k);
// The inverse of to_string; throws std::invalid_argument (one line, naming the
// valid names) for an unknown name.
FindingKind finding_kind_from_name(std::string_view name);

}  // namespace odotune::diagnose
