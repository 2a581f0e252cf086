// The fitness modes an EKF or UKF tune minimises. Modes 1..7 are the seven of
// Kovacs et al. §2.3.4 and score against ground truth; modes 8 and 9 need
// none: they cross-validate over the position fixes
// (odotune/objectives/fix_cv_replay.h). Each mode keeps the paper's number, which is
// also the number a results store records (odotune/results/run_record.h) and the
// command line takes, beside a name.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace odotune::objectives {

enum class FitnessMode : int {
  rmse = 1,           // 1: RMSE [m]
  mae = 2,            // 2: MAE [m]
  maxe = 3,           // 3: MAXE [m]
  rmse_mae = 4,       // 4: RMSE + MAE [m]
  rmse_maxe = 5,      // 5: RMSE + MAXE [m]
  mae_maxe = 6,       // 6: MAE + MAXE [m]
  rmse_mae_maxe = 7,  // 7: RMSE + MAE + MAXE [m]
  fix_rmse = 8,       // 8: RMSE of the held-out fixes' prediction errors [m]
  fix_nll = 9,        // 9: mean negative log predictive likelihood of the held-out fixes [nats]
};

// The mode a tune, demo, grid or report uses when none is given (the study's).
inline constexpr FitnessMode kDefaultFitnessMode = FitnessMode::rmse_mae_maxe;

// The seven modes against ground truth, in the paper's order (the rows of its
// Figure 3), and all nine.
inline constexpr std::array<FitnessMode, 7> kGroundTruthModes = {
    FitnessMode::rmse,      FitnessMode::mae,      FitnessMode::maxe,         FitnessMode::rmse_mae,
    FitnessMode::rmse_maxe, FitnessMode::mae_maxe, FitnessMode::rmse_mae_maxe};
inline constexpr std::array<FitnessMode, 9> kAllFitnessModes = {
    FitnessMode::rmse,          FitnessMode::mae,       FitnessMode::maxe,
    FitnessMode::rmse_mae,      FitnessMode::rmse_maxe, FitnessMode::mae_maxe,
    FitnessMode::rmse_mae_maxe, FitnessMode::fix_rmse,  FitnessMode::fix_nll};

// The paper's (and the store's) number of a mode, 1..9.
inline constexpr int number(FitnessMode m) { return static_cast<int>(m); }
// The numbers of kGroundTruthModes, 1..7.
std::vector<int> ground_truth_mode_numbers();
// The mode of a number 1..9; nullopt for any other.
std::optional<FitnessMode> fitness_mode_of_number(int n);

// True for modes 8 and 9, which score held-out fixes instead of ground truth.
bool is_fix_cv(FitnessMode m);

// Human-readable name in outputs, e.g. "RMSE+MAE", "held-out fix NLL".
std::string fitness_mode_name(FitnessMode m);
// The name the command line and experiment files take besides the number,
// e.g. "rmse+mae", "fix-nll".
std::string_view fitness_mode_key(FitnessMode m);

// Parses a number ("7") or a key ("rmse+mae+maxe"); false for anything else.
bool parse_fitness_mode(std::string_view text, FitnessMode* out);
// What parse_fitness_mode takes, for messages: "1..9 or rmse, mae, …,
// fix-nll"; with `ground_truth_only`, "1..7 or rmse, …, rmse+mae+maxe".
std::string fitness_mode_choices(bool ground_truth_only = false);

}  // namespace odotune::objectives
