#include <odotune/results/diagnosis_report.h>

#include <stdlib.h>  // NOLINT(modernize-deprecated-headers): mkdtemp is POSIX, declared by stdlib.h

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include <fmt/format.h>

#include <odotune/core/atomic_file.h>
#include <odotune/results/report_html.h>

namespace odotune::results {
namespace fs = std::filesystem;

namespace {

// The figure stems diagnosis_figures() may write, in page order.
constexpr const char* kStems[] = {"residual_time", "residual_condition", "map", "overlay"};

// A private folder inside the report folder (same file system, so its files
// can be renamed into place), removed with its content when it goes.
class StagingDir {
 public:
  explicit StagingDir(const fs::path& parent) {
    std::string tmpl = (parent / ".diagnosis-report-XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr)
      throw std::runtime_error(fmt::format("cannot write the diagnosis report into {}: {}", parent.string(),
                                           std::strerror(errno)));
    path_ = tmpl;
  }
  ~StagingDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  StagingDir(const StagingDir&) = delete;
  StagingDir& operator=(const StagingDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read the figure " + p.string());
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// What figure `stem` shows, for the caption under it.
std::string caption(const std::string& stem, const DiagnosisFigureData& d) {
  const std::string after = d.finding.empty() ? "the corrected model"
                                              : fmt::format("the finding ({})", d.finding);
  if (stem == "residual_time") {
    std::string s = "Position error |predicted − reference| of the odometry replay at every reference "
                    "sample, the replay re-anchored to the reference at each window start (dotted lines). ";
    s += d.after_pos_err_m.empty() ? "There is no finding, so only the nominal model's error is shown."
                                   : fmt::format("Before: nominal model; after: with {}.", after);
    if (!d.segments.empty()) s += " Shaded: the located segments.";
    return s;
  }
  if (stem == "residual_condition") {
    std::string s = fmt::format(
        "{} against {}: the rows as thin points (every k-th when there are very many) and the "
        "median in quantile bins of the condition as a line. ",
        d.residual_label, d.condition_label);
    s += d.after_residual.empty()
             ? "There is no finding, so only the nominal model is shown; a trend of the median "
               "with the condition is the unexplained effect."
             : fmt::format("Before: nominal model; after: with {}. A trend in the before median "
                           "that is flat after is the effect the finding explains.",
                           after);
    return s;
  }
  if (stem == "map") {
    std::string s = "The reference path (grey) with equal axis scale";
    if (!d.flagged.empty()) s += "; red: samples whose residual exceeds the noise level";
    s += d.regions.empty() ? "; no region was located."
                           : "; boxes: the located regions (region 1, 2, … in the order of the result).";
    return s;
  }
  std::vector<std::string> names;
  for (const auto& p : d.overlay) names.push_back(p.name);
  return fmt::format("Trajectories over the whole track, equal axis scale: {}.", fmt::join(names, "; "));
}

const char* heading(const std::string& stem) {
  if (stem == "residual_time") return "Residual vs time";
  if (stem == "residual_condition") return "Residual vs the responsible condition";
  if (stem == "map") return "Where: located regions on the map";
  return "Trajectory overlay";
}

struct PageFigure {
  std::string stem;  // file stem inside the report folder
  std::string svg;   // the SVG file's text
};

std::string page_html(const DiagnosisFigureData& d, const std::vector<std::string>& summary,
                      const std::vector<PageFigure>& figures, const std::string& json_text) {
  HtmlPage page("odotune diagnose: " + d.track);
  page.heading("Summary");
  if (summary.empty()) {
    page.paragraph("(no summary)");
  } else {
    page.list(summary);
  }
  std::vector<std::string> files;
  for (const auto& f : figures) {
    page.heading(heading(f.stem));
    page.figures({{caption(f.stem, d), f.svg, "", f.stem + "-"}});
    files.push_back(f.stem + ".png");
    files.push_back(f.stem + ".svg");
  }
  page.heading("Result (JSON)");
  page.preformatted(json_text);
  page.paragraph(fmt::format("The figures are also in this folder as files: {}.", fmt::join(files, ", ")));
  return page.html();
}

}  // namespace

void write_diagnosis_report(const fs::path& dir, const DiagnosisFigureData& data,
                            const std::vector<std::string>& summary_lines, const std::string& json_text) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw std::runtime_error(fmt::format("{}: cannot create the report folder: {}", dir.string(),
                                         ec ? ec.message() : "not a folder"));

  const StagingDir staging(dir);
  const std::vector<fs::path> drawn = diagnosis_figures(staging.path(), data);
  std::vector<PageFigure> figures;
  for (const auto& stem : drawn) {
    const std::string name = stem.filename().string();
    figures.push_back({name, slurp(fs::path(stem) += ".svg")});
  }
  const std::string html = page_html(data, summary_lines, figures, json_text);

  // Everything is ready: move the figures into place, drop a stale figure of
  // an earlier report that this one does not have, then write the page.
  for (const auto& f : figures) {
    for (const char* ext : {".png", ".svg"}) {
      const fs::path from = staging.path() / (f.stem + ext), to = dir / (f.stem + ext);
      fs::rename(from, to, ec);
      if (ec)
        throw std::runtime_error(fmt::format("cannot move the figure {} into place: {}", to.string(),
                                             ec.message()));
    }
  }
  for (const char* stem : kStems) {
    bool written = false;
    for (const auto& f : figures) written = written || f.stem == stem;
    if (written) continue;
    for (const char* ext : {".png", ".svg"}) fs::remove(dir / (std::string(stem) + ext), ec);
  }
  core::write_atomically(dir / "index.html", "diagnosis report page", html);
}

}  // namespace odotune::results
