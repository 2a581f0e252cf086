#include "objectives/metrics.h"

namespace odotune {

std::string fitness_mode_name(int mode) {
  static const char* names[] = {"RMSE",
                                "MAE",
                                "MAXE",
                                "RMSE+MAE",
                                "RMSE+MAXE",
                                "MAE+MAXE",
                                "RMSE+MAE+MAXE",
                                "held-out fix RMSE",
                                "held-out fix NLL"};
  return valid_ekf_fitness_mode(mode) ? names[mode - 1] : "invalid";
}

}  // namespace odotune
