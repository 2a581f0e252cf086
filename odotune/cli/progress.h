// Progress of long work on stderr: "label  done/total  rate/s  ETA", redrawn
// in place. Shown only when stderr is a terminal and CI is not set, so logs
// and CI stay quiet. Call update() from one thread.
#pragma once

#include <chrono>
#include <string>

namespace odotune::cli {

// True when progress is shown: stderr is a terminal and CI is not set.
bool progress_shown();

class Progress {
 public:
  Progress(std::string label, std::string unit);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void update(long done, long total);
  void set_label(std::string label) { label_ = std::move(label); }
  // Clears the line (called by the destructor).
  void finish();
  bool enabled() const { return enabled_; }

 private:
  std::string label_, unit_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

// One status line on stderr for work that reports no counts (e.g. a
// calibration run), shown under the same rule as Progress and cleared when the
// object goes (the work ended or threw).
class StatusLine {
 public:
  explicit StatusLine(const std::string& text);
  ~StatusLine();
  StatusLine(const StatusLine&) = delete;
  StatusLine& operator=(const StatusLine&) = delete;

 private:
  bool enabled_;
};

}  // namespace odotune::cli
