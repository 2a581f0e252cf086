// Experiment files for `odotune grid` (see experiments/*.yaml, commented):
//
//   format: odotune-experiment/1
//   name: study
//   models: [rq, alpha, gyro]
//   tracks: [../data/tracks/track*.csv]   # paths or globs, relative to this file
//   modes: [1, 2, 3, 4, 5, 6, 7]
//   seeds: {first: 1, count: 20}         # or a list: [1, 2, 3]
//   solver: pso                          # or nlopt:NAME
//   budget: {particles: 50, iterations: 150}   # nlopt: {evaluations: 7550}
//   leave_one_out: false                 # also tune on all tracks but one, score on it
//   store: ../results/study.sqlite       # relative to this file
//
// Errors are one line: "FILE:LINE: what is wrong, what was expected".
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "filters/ekf_noise.h"

namespace odotune::cli {

struct Experiment {
  std::filesystem::path file;
  std::string text;  // the file verbatim (hashed into the store)
  std::string name;
  std::vector<filters::NoiseModel> models;
  std::vector<std::string> tracks;  // resolved paths, sorted within each glob
  std::vector<int> modes;
  std::vector<std::uint64_t> seeds;
  std::string solver = "pso";
  int particles = 50, iterations = 150;
  long evaluations = 0;
  bool leave_one_out = false;
  std::filesystem::path store;
};

// Throws odotune::cli::Failure.
Experiment read_experiment(const std::filesystem::path& path);
// The same for an experiment's text as if read from `path` (relative paths
// in it resolve against path's folder), e.g. the text kept in a results
// store. Throws odotune::cli::Failure.
Experiment parse_experiment(const std::string& text, const std::filesystem::path& path);

}  // namespace odotune::cli
