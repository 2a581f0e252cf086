// Checks of an output file's path before long work starts, so that a typo in
// --json or --model-out fails at once with one line instead of after the run.
// Both do nothing for an empty path (the output was not asked for) and throw
// core::Failure ("FLAG PATH: …") otherwise.
#pragma once

#include <string>

namespace odotune::core {

// The path's directory exists: "--json out/x.json: the directory out does not exist".
void check_output_dir(const std::string& flag, const std::string& path);
// As check_output_dir, and the path is not itself a folder:
// "--model-out models: is a folder; expected a file name".
void check_output_file(const std::string& flag, const std::string& path);

}  // namespace odotune::core
