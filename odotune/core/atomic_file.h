// Writing a file so that it appears whole or not at all: the content goes to a
// temporary beside the target (unique per process and call), which is then
// renamed over the target. Every writer of the project (tracks, configurations,
// JSON results, exports) goes through here, so a failure never leaves a
// partial output file.
#pragma once

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string_view>

namespace odotune::core {

// `fill` writes the content to the stream. On any failure (cannot create the
// temporary, `fill` throws, write error, rename fails) the temporary is
// removed and std::runtime_error "cannot write WHAT 'PATH': reason" is thrown.
void write_atomically(const std::filesystem::path& path, std::string_view what,
                      const std::function<void(std::ostream&)>& fill);
void write_atomically(const std::filesystem::path& path, std::string_view what, std::string_view text);

}  // namespace odotune::core
