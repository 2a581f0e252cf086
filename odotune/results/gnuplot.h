// Runs one gnuplot script in isolation and moves its outputs into place.
//
// Contract of run_gnuplot():
//  - Creates a fresh private temp dir, writes the job's data files and the
//    script there, and runs `gnuplot script.gp` (found on PATH, started with
//    posix_spawnp, no shell) with that dir as the script's only workspace.
//  - gnuplot runs with the temp dir as working directory, so the script
//    refers to data files and outputs by their plain file names.
//  - On success each output is copied next to its destination as DEST.tmp
//    and then renamed over DEST (atomic per file). Either all destinations
//    are written or none is: on any error every DEST.tmp is removed and the
//    temp dir is deleted.
//  - Throws std::runtime_error with one clear line when gnuplot is not
//    installed, when a destination directory does not exist, when gnuplot
//    fails (its exit status and first error line are quoted) or when an
//    output was not produced.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace odotune::results {

struct GnuplotJob {
  // Data files to write into the temp dir: {file name, content}. Names are
  // plain file names (no directory part).
  std::vector<std::pair<std::string, std::string>> data_files;
  // The gnuplot script; file names are relative to the temp dir, e.g.
  // "set output 'out.png'".
  std::string script;
  // Outputs the script writes: {file name in the temp dir, destination}.
  std::vector<std::pair<std::string, std::filesystem::path>> outputs;
};

// Runs the job as described above. Throws std::runtime_error on failure.
void run_gnuplot(const GnuplotJob& job);

// Renders `body` (gnuplot settings + one plot command, reading `data_files`
// by their names) to STEM.png (pngcairo) and STEM.svg, both or neither, at
// width_px x height_px, texts verbatim (noenhanced). Throws
// std::invalid_argument for a stem without a file name, else as run_gnuplot.
void render_png_svg(const std::filesystem::path& stem,
                    std::vector<std::pair<std::string, std::string>> data_files, const std::string& body,
                    int width_px, int height_px);

// Appends the two files render_png_svg writes for `stem`, STEM.png and
// STEM.svg, to `files` (a study's list of what it wrote).
inline void append_png_svg(const std::filesystem::path& stem, std::vector<std::filesystem::path>* files) {
  files->push_back(std::filesystem::path(stem.string() + ".png"));
  files->push_back(std::filesystem::path(stem.string() + ".svg"));
}

// True when a `gnuplot` executable is found on PATH.
bool gnuplot_available();

// `text` as a gnuplot single-quoted string literal (quotes doubled, newlines
// and other control characters replaced by spaces; backslashes stay literal
// in single quotes). Use with `noenhanced` so `_` and `^` are not markup.
std::string gnuplot_quote(std::string_view text);

// A number as written into gnuplot data and commands (10 significant digits).
std::string gnuplot_number(double v);

// Colour of series i: ten distinguishable colours (Tableau 10), i modulo 10;
// a negative i is black (a reference line: ground truth, a truth value).
std::string series_colour(int i);

// Screen margins (top, bottom) of panel p of n panels stacked between
// y = 0.10 and 0.90 of the canvas, 0.07 apart (multiplot layouts).
std::pair<double, double> stacked_panel_span(std::size_t p, std::size_t n);

}  // namespace odotune::results
