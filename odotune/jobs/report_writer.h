// Pieces every report page uses (odotune/jobs/report_job.cpp, odotune/jobs/rl_report.cpp):
// the folder writer that collects files and HTML figures, and small text
// helpers. Internal to jobs/.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include <odotune/core/atomic_file.h>
#include <odotune/core/failure.h>
#include <odotune/results/gnuplot.h>
#include <odotune/results/report_html.h>
#include <odotune/results/run_record.h>

namespace odotune::jobs {

// A name usable in a file name: letters, digits, '-', '_', '.' kept.
std::string file_safe(const std::string& s);
std::string lower(std::string_view s);
// "1 seed" or "mean over N seeds" for the runs' distinct seeds.
std::string seeds_phrase(const std::vector<results::RunRecord>& runs);

// Writes a report's files into one folder and collects their paths.
class ReportWriter {
 public:
  explicit ReportWriter(std::filesystem::path dir) : dir_(std::move(dir)) {}

  // Renders a figure through `draw(stem)`; returns it for the HTML page.
  // Throws Failure naming the figure when drawing fails.
  template <typename Draw>
  results::HtmlFigure figure(const std::string& name, const std::string& caption, Draw&& draw) {
    const std::filesystem::path stem = dir_ / name;
    try {
      draw(stem);
    } catch (const std::exception& ex) {
      throw core::Failure(fmt::format("{}: cannot draw the figure: {}", stem.string(), ex.what()));
    }
    results::append_png_svg(stem, &files);
    return {caption, svg_of(stem.string() + ".svg"), name + ".png", ""};
  }
  // Writes `content` atomically; throws Failure with one line.
  void text(const std::string& name, const std::string& what, const std::string& content);
  // Ends `page` with a paragraph per note, writes it as index.html and
  // returns every file written, in order.
  std::vector<std::filesystem::path> finish(results::HtmlPage& page, const std::vector<std::string>& notes);

  std::vector<std::filesystem::path> files;

 private:
  static std::string svg_of(const std::filesystem::path& p);
  std::filesystem::path dir_;
};

}  // namespace odotune::jobs
