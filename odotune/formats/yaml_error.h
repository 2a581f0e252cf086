// The one-line errors of the CLI's YAML readers: "FILE:LINE: what is wrong,
// what was expected" (just "FILE: ..." when the node has no position), and the
// opening every versioned file shares (load, a mapping, its `format:` line).
#pragma once

#include <filesystem>
#include <string>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <odotune/core/failure.h>

namespace odotune::formats {

[[noreturn]] inline void fail_at(const std::filesystem::path& path, const YAML::Node& node,
                                 const std::string& what) {
  const auto mark = node.Mark();
  if (mark.is_null()) throw core::Failure(fmt::format("{}: {}", path.string(), what));
  throw core::Failure(fmt::format("{}:{}: {}", path.string(), mark.line + 1, what));
}

// Loads `path` ("cannot open the WHAT" when unreadable, the parser's line on a
// syntax error) and checks it is a mapping (else "expected " + mapping_hint)
// whose `format` is `format`. Throws core::Failure.
inline YAML::Node load_format_file(const std::filesystem::path& path, const std::string& what,
                                   const std::string& format, const std::string& mapping_hint) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path.string());
  } catch (const YAML::BadFile&) {
    throw core::Failure(fmt::format("{}: cannot open the {}", path.string(), what));
  } catch (const YAML::ParserException& e) {
    throw core::Failure(fmt::format("{}:{}: {}", path.string(), e.mark.line + 1, e.msg));
  }
  if (!root.IsMap()) fail_at(path, root, "expected " + mapping_hint);
  const YAML::Node f = root["format"];
  if (!f || !f.IsScalar() || f.Scalar() != format)
    fail_at(path, f ? f : root, fmt::format("missing or unknown format, expected 'format: {}'", format));
  return root;
}

}  // namespace odotune::formats
