#include <odotune/diagnose/finding_kind.h>

namespace odotune::diagnose {

namespace {
constexpr std::string_view kUnexplainedName = "unexplained";
}  // namespace

std::string_view to_string(const FindingKind& k) {
  if (const Effect* e = std::get_if<Effect>(&k)) return effect_name(*e);
  return kUnexplainedName;
}

FindingKind finding_kind_from_name(std::string_view name) {
  if (name == kUnexplainedName) return Unexplained{};
  return effect_from_name(name);
}

}  // namespace odotune::diagnose
