#include <odotune/core/atomic_file.h>

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include <fmt/format.h>

namespace odotune::core {

void write_atomically(const std::filesystem::path& path, std::string_view what,
                      const std::function<void(std::ostream&)>& fill) {
  namespace fs = std::filesystem;
  static std::atomic<unsigned> counter{0};
  fs::path tmp = path;
  tmp += fmt::format(".tmp-{}-{}", static_cast<long>(::getpid()), counter.fetch_add(1));
  const auto fail = [&](const std::string& why) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw std::runtime_error(fmt::format("cannot write {} '{}': {}", what, path.string(), why));
  };
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out)
      fail(fmt::format("cannot create '{}' (does the directory exist?): {}", tmp.string(),
                       std::generic_category().message(errno)));
    try {
      fill(out);
      out.close();
    } catch (const std::exception& e) {
      out.close();
      fail(e.what());
    }
    if (out.fail()) fail(fmt::format("error writing '{}'", tmp.string()));
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) fail(fmt::format("cannot rename '{}' to it: {}", tmp.string(), ec.message()));
}

void write_atomically(const std::filesystem::path& path, std::string_view what, std::string_view text) {
  write_atomically(path, what, [text](std::ostream& out) {
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
  });
}

}  // namespace odotune::core
