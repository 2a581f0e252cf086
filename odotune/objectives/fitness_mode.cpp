#include <odotune/objectives/fitness_mode.h>

#include <charconv>

#include <fmt/format.h>

namespace odotune::objectives {

std::vector<int> ground_truth_mode_numbers() {
  std::vector<int> out;
  out.reserve(kGroundTruthModes.size());
  for (FitnessMode m : kGroundTruthModes) out.push_back(number(m));
  return out;
}

std::optional<FitnessMode> fitness_mode_of_number(int n) {
  for (FitnessMode m : kAllFitnessModes)
    if (number(m) == n) return m;
  return std::nullopt;
}

bool is_fix_cv(FitnessMode m) {
  switch (m) {
    case FitnessMode::rmse:
    case FitnessMode::mae:
    case FitnessMode::maxe:
    case FitnessMode::rmse_mae:
    case FitnessMode::rmse_maxe:
    case FitnessMode::mae_maxe:
    case FitnessMode::rmse_mae_maxe: return false;
    case FitnessMode::fix_rmse:
    case FitnessMode::fix_nll: return true;
  }
  return false;
}

std::string fitness_mode_name(FitnessMode m) {
  switch (m) {
    case FitnessMode::rmse: return "RMSE";
    case FitnessMode::mae: return "MAE";
    case FitnessMode::maxe: return "MAXE";
    case FitnessMode::rmse_mae: return "RMSE+MAE";
    case FitnessMode::rmse_maxe: return "RMSE+MAXE";
    case FitnessMode::mae_maxe: return "MAE+MAXE";
    case FitnessMode::rmse_mae_maxe: return "RMSE+MAE+MAXE";
    case FitnessMode::fix_rmse: return "held-out fix RMSE";
    case FitnessMode::fix_nll: return "held-out fix NLL";
  }
  return "invalid";
}

std::string_view fitness_mode_key(FitnessMode m) {
  switch (m) {
    case FitnessMode::rmse: return "rmse";
    case FitnessMode::mae: return "mae";
    case FitnessMode::maxe: return "maxe";
    case FitnessMode::rmse_mae: return "rmse+mae";
    case FitnessMode::rmse_maxe: return "rmse+maxe";
    case FitnessMode::mae_maxe: return "mae+maxe";
    case FitnessMode::rmse_mae_maxe: return "rmse+mae+maxe";
    case FitnessMode::fix_rmse: return "fix-rmse";
    case FitnessMode::fix_nll: return "fix-nll";
  }
  return "invalid";
}

bool parse_fitness_mode(std::string_view text, FitnessMode* out) {
  int n = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
  if (ec == std::errc() && end == text.data() + text.size()) {
    const std::optional<FitnessMode> m = fitness_mode_of_number(n);
    if (m) *out = *m;
    return m.has_value();
  }
  for (FitnessMode m : kAllFitnessModes)
    if (fitness_mode_key(m) == text) {
      *out = m;
      return true;
    }
  return false;
}

std::string fitness_mode_choices(bool ground_truth_only) {
  std::string keys;
  int last = 0;
  for (FitnessMode m : kAllFitnessModes) {
    if (ground_truth_only && is_fix_cv(m)) continue;
    keys += fmt::format("{}{}", keys.empty() ? "" : ", ", fitness_mode_key(m));
    last = number(m);
  }
  return fmt::format("1..{} or {}", last, keys);
}

}  // namespace odotune::objectives
