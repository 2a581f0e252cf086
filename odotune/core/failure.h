// The CLI's single error type: one line for the user, and an exit code.
#pragma once

#include <stdexcept>
#include <string>

namespace odotune::core {

struct Failure : std::runtime_error {
  explicit Failure(const std::string& line, int code = 1) : std::runtime_error(line), exit_code(code) {}
  int exit_code;
};

}  // namespace odotune::core
