// Either of robot_localization's filters, picked at run time as its nodes
// are: ekf_node (odotune/filters/rl_ekf.h) or ukf_node (odotune/filters/rl_ukf.h), behind
// the interface the node's plumbing (odotune/rlnode/replay.h) drives.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <variant>

#include <odotune/filters/rl_ekf.h>
#include <odotune/filters/rl_ukf.h>

namespace odotune::filters::rl {

enum class RlFilterType { ekf, ukf };
inline constexpr std::array<RlFilterType, 2> kAllRlFilterTypes = {RlFilterType::ekf, RlFilterType::ukf};
std::string_view to_string(RlFilterType t);     // "ekf", "ukf"
std::string_view display_name(RlFilterType t);  // "EKF", "UKF", for text a user reads
std::optional<RlFilterType> parse_rl_filter_type(std::string_view name);

// The unscented transform's constants (ukf_node's ~alpha, ~kappa, ~beta).
struct UkfConstants {
  double alpha = 0.001;
  double kappa = 0.0;
  double beta = 2.0;
};

class RlFilter {
 public:
  // Throws std::invalid_argument for invalid parameters (RlEkfParams::IsValid,
  // RlUkfParams::IsValid).
  RlFilter(RlFilterType type, const RlEkfParams& params, const UkfConstants& ukf = {});

  RlFilterType type() const {
    return std::holds_alternative<RlEkf>(f_) ? RlFilterType::ekf : RlFilterType::ukf;
  }
  bool process(const Measurement& m);
  void predict_to(std::int64_t time_ns);
  void predict(double dt_s);
  // The latest command (use_control). The EKF's prediction uses it;
  // ukf_node's computes the control term but does not apply it (ukf.cpp's
  // projection has no control), so the UKF ignores it.
  void set_command(const Command& c);
  // RlEkf::restore, RlUkf::restore.
  void restore(const State& x, const Cov& P, std::int64_t last_ns);

  bool initialized() const;
  std::int64_t last_time_ns() const;
  const State& state() const;
  const Cov& cov() const;

 private:
  std::variant<RlEkf, RlUkf> f_;
};

}  // namespace odotune::filters::rl
