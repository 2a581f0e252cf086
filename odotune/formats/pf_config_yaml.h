// Tuned particle-filter calibrator settings as YAML: the file `tune --model
// pf-calib|adaptive-pf-calib --config-out` writes, for `calibrate` to read.
//
//   format: odotune-pf-config/1
//   method: adaptive-pf        # pf | adaptive-pf (calibration_run.h's names)
//   resampler: systematic      # multinomial | stratified | systematic | residual
//   policy: neff               # every | neff | max
//   particles: 8000            # N (pf) or the initial N (adaptive-pf), ≥ 1
//   params:                    # calibration_space() names and units, all five
//     neff_fraction: 0.5                 # [-]
//     max_weight_ratio: 10               # [-]
//     alpha: 0.0001                      # [m/(m/s)]
//     dispersion_per_particle_mm: 0.01   # [mm]
//     random_walk_sigma_mm: 0.5          # [mm]
//
// Not in the file: the initial ranges (they belong to the robot, not to the
// tuning), the seed and the thread count (choices of each run). Values
// outside the tuning bounds are accepted (a file may be edited by hand) as
// long as the resulting PfCalibratorParams are valid.
//
// Reading errors are one line: "FILE:LINE: what is wrong, what was expected".
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <odotune/calibration/calibration_run.h>
#include <odotune/filters/pf_calibrator.h>

namespace odotune::formats {

struct PfConfig {
  calibration::CalibrationMethod method = calibration::CalibrationMethod::adaptive_pf;  // pf or adaptive_pf
  filters::Resampler resampler = filters::Resampler::systematic;
  filters::ResamplePolicy policy = filters::ResamplePolicy::neff;
  int particles = 8000;
  std::vector<double> params;  // physical values, calibration_space() order and units
  std::string comment;         // written as leading YAML comments (provenance)
};

// The file's settings applied to `base` (which keeps its ranges, seed,
// threads, perturbations and particle limits): resampler, policy, particles,
// adaptive (from the method) and the five tuned values (SI inside).
filters::PfCalibratorParams apply_pf_config(const PfConfig& config, const filters::PfCalibratorParams& base);

// Throws core::Failure ("FILE:LINE: ...").
PfConfig read_pf_config(const std::filesystem::path& path);
// Writes atomically (temporary + rename). Throws core::Failure.
void write_pf_config(const PfConfig& config, const std::filesystem::path& path);

}  // namespace odotune::formats
