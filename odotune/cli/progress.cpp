#include <odotune/cli/progress.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>

#include <fmt/format.h>

namespace odotune::cli {

bool progress_shown() { return isatty(STDERR_FILENO) != 0 && std::getenv("CI") == nullptr; }

StatusLine::StatusLine(const std::string& text) : enabled_(progress_shown()) {
  if (!enabled_) return;
  std::fputs(text.c_str(), stderr);
  std::fflush(stderr);
}

StatusLine::~StatusLine() {
  if (!enabled_) return;
  std::fputs("\r\x1b[2K", stderr);
  std::fflush(stderr);
}

Progress::Progress(std::string label, std::string unit)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      enabled_(progress_shown()),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

Progress::~Progress() { finish(); }

void Progress::update(long done, long total) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (drawn_ && done < total && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  const double secs = std::chrono::duration<double>(now - start_).count();
  const double rate = secs > 0 ? static_cast<double>(done) / secs : 0.0;
  const double eta = rate > 0 ? static_cast<double>(total - done) / rate : 0.0;
  std::fputs(fmt::format("\r\x1b[2K{}  {}/{} {}  {:.0f}/s  ETA {:.0f} s", label_, done, total, unit_, rate, eta)
                 .c_str(),
             stderr);
  std::fflush(stderr);
  drawn_ = true;
}

void Progress::finish() {
  if (enabled_ && drawn_) {
    std::fputs("\r\x1b[2K", stderr);
    std::fflush(stderr);
  }
  drawn_ = false;
}

}  // namespace odotune::cli
