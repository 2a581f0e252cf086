// Runs the built odotune binary for end-to-end tests.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "support/temp_dir.h"

namespace odotune::testing_support {

struct CliResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Runs `odotune ARGS` through the shell with CI=1 (no progress output).
inline CliResult run_cli(const std::string& args) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("odotune_cli_" + std::to_string(::getpid()) + "_" + std::to_string(std::rand()));
  std::filesystem::create_directories(dir);
  const std::string cmd = "CI=1 " + std::string(ODOTUNE_BINARY) + " " + args + " >" + (dir / "out").string() +
                          " 2>" + (dir / "err").string();
  const int status = std::system(cmd.c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(dir / "out");
  r.err = slurp(dir / "err");
  std::filesystem::remove_all(dir);
  return r;
}

// The number printed right after `label` in `text` (label is a regex), or
// -1e300 when there is none.
inline double number_after(const std::string& text, const std::string& label) {
  const std::regex re(label + R"(\s*([-0-9.]+))");
  std::smatch m;
  if (!std::regex_search(text, m, re)) return -1e300;
  return std::stod(m[1]);
}

inline std::string reference_track(int i) {
  return std::string(ODOTUNE_SOURCE_DIR) + "/data/tracks/track" + std::to_string(i) + ".csv";
}

}  // namespace odotune::testing_support
