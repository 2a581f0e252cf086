// The one-line error of every YAML reader in the CLI: "FILE:LINE: what is
// wrong, what was expected" (just "FILE: ..." when the node has no position).
#pragma once

#include <filesystem>
#include <string>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "cli/failure.h"

namespace odotune::cli {

[[noreturn]] inline void fail_at(const std::filesystem::path& path, const YAML::Node& node,
                                 const std::string& what) {
  const auto mark = node.Mark();
  if (mark.is_null()) throw Failure(fmt::format("{}: {}", path.string(), what));
  throw Failure(fmt::format("{}:{}: {}", path.string(), mark.line + 1, what));
}

}  // namespace odotune::cli
