// Tuned velocity-fusion UKF noise as YAML: the file `tune --model ukf
// --config-out` and `export --format odotune` of a ukf run write, and what
// reads it back (read_ukf_config):
//
//   format: odotune-ukf-config/1
//   rate_hz: 10                # fusion rate [Hz] the values were tuned at
//   params:                    # ukf_space() names and units, all six
//     q_v_m2_s3: 0.05          # [(m/s)²/s]
//     q_w_rad2_s3: 0.1         # [(rad/s)²/s]
//     odo_var_v: 0.001         # [(m/s)²]
//     odo_var_w: 0.001         # [(rad/s)²]
//     gyro_var: 4e-06          # [(rad/s)²]
//     ext_var_scale: 1         # [-]
//
// The writer adds comments explaining each value and the model (Fariña et
// al., Sensors 2023, 23, 961, §1). The variances are per fusion step, so
// they belong to the rate: a file is only meaningful at its rate_hz. Values
// outside the tuning bounds are accepted (a file may be edited by hand) as
// long as they are finite and > 0. Not in the file: the unscented
// transform's α, β, κ and the initial state (UkfParams' defaults).
//
// Reading errors are one line: "FILE:LINE: what is wrong, what was expected".
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <odotune/learned/ukf_objective.h>

namespace odotune::formats {

struct UkfConfig {
  double rate_hz = 10.0;       // fusion rate [Hz]
  std::vector<double> params;  // physical values, ukf_space() order and units
  std::string comment;         // written as leading YAML comments (provenance)
};

// The file's values applied to `base` (apply_ukf_params).
learned::UkfSettings apply_ukf_config(const UkfConfig& config, const learned::UkfSettings& base = {});

// Throws core::Failure ("FILE:LINE: ...").
UkfConfig read_ukf_config(const std::filesystem::path& path);
// Writes atomically (temporary + rename). Throws core::Failure.
void write_ukf_config(const UkfConfig& config, const std::filesystem::path& path);

}  // namespace odotune::formats
