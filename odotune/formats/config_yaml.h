// Tuned EKF configurations as YAML, the file `tune --config-out` writes and
// `eval --config` reads (and `export --format odotune` will write):
//
//   format: odotune-ekf-config/1
//   model: rq                 # rq | alpha | gyro
//   params:                   # the model's parameters, names as in `tune --help`
//     r1_mm2: 123.4
//     ...
//
// Reading errors are one line: "FILE:LINE: what is wrong, what was expected".
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <odotune/filters/ekf_noise.h>

namespace odotune::formats {

struct EkfConfig {
  filters::NoiseModel model = filters::NoiseModel::rq;
  filters::NoiseParams noise;
  std::string comment;  // written as a leading YAML comment (provenance)
};

// Throws core::Failure.
EkfConfig read_ekf_config(const std::filesystem::path& path);
// Writes atomically (temporary + rename). Throws core::Failure.
void write_ekf_config(const EkfConfig& config, const std::filesystem::path& path);

// Writes `text` to `path` atomically; throws core::Failure.
void write_file_atomically(const std::filesystem::path& path, const std::string& text);

}  // namespace odotune::formats
