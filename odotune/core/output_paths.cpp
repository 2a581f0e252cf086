#include <odotune/core/output_paths.h>

#include <filesystem>
#include <system_error>

#include <fmt/format.h>

#include <odotune/core/failure.h>

namespace odotune::core {

namespace fs = std::filesystem;

void check_output_dir(const std::string& flag, const std::string& path) {
  if (path.empty()) return;
  const fs::path parent = fs::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty() && !fs::is_directory(parent, ec))
    throw Failure(fmt::format("{} {}: the directory {} does not exist", flag, path, parent.string()));
}

void check_output_file(const std::string& flag, const std::string& path) {
  if (path.empty()) return;
  std::error_code ec;
  if (fs::is_directory(fs::path(path), ec))
    throw Failure(fmt::format("{} {}: is a folder; expected a file name", flag, path));
  check_output_dir(flag, path);
}

}  // namespace odotune::core
