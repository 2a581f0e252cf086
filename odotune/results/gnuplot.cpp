#include <odotune/results/gnuplot.h>

#include <cstdio>

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

extern char** environ;

namespace odotune::results {
namespace fs = std::filesystem;

namespace {

constexpr const char* kNotInstalled =
    "gnuplot is not installed (no `gnuplot` executable on PATH); install the Debian package "
    "gnuplot-nox, e.g. with scripts/install-deps.sh";

// A private temp dir, removed with everything in it when it goes out of scope.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "odotune-gnuplot-XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr) {
      throw std::runtime_error("cannot create a temp dir for gnuplot in " + fs::temp_directory_path().string() +
                               ": " + std::strerror(errno));
    }
    path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

void write_file(const fs::path& path, const std::string& content) {
  std::ofstream out(path, std::ios::binary);
  out << content;
  out.close();
  if (!out) throw std::runtime_error("cannot write gnuplot input file " + path.string());
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The most telling line of gnuplot's log: the first one naming a script line
// (gnuplot reports errors as `"script.gp" line N: message`), else the last
// non-empty one.
std::string first_error_line(const std::string& log) {
  std::istringstream in(log);
  std::string line, last;
  while (std::getline(in, line)) {
    if (line.find("\"script.gp\" line") != std::string::npos) return line;
    if (line.find_first_not_of(" \t\r^") != std::string::npos) last = line;
  }
  return last.empty() ? "(no message)" : last;
}

bool is_plain_name(const std::string& name) {
  return !name.empty() && name.find('/') == std::string::npos && name != "." && name != "..";
}

// Runs `gnuplot script.gp` in `dir` with stdout+stderr to dir/gnuplot.log;
// returns the wait status. Throws when gnuplot cannot be started.
int spawn_gnuplot(const fs::path& dir) {
  posix_spawn_file_actions_t actions;
  if (posix_spawn_file_actions_init(&actions) != 0) {
    throw std::runtime_error("cannot start gnuplot: posix_spawn_file_actions_init failed");
  }
  struct Guard {
    posix_spawn_file_actions_t* a;
    ~Guard() { posix_spawn_file_actions_destroy(a); }
  } guard{&actions};
  const std::string dir_str = dir.string();
  int rc = posix_spawn_file_actions_addchdir_np(&actions, dir_str.c_str());
  if (rc == 0) rc = posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  if (rc == 0) {
    rc = posix_spawn_file_actions_addopen(&actions, 1, "gnuplot.log", O_WRONLY | O_CREAT | O_TRUNC, 0644);
  }
  if (rc == 0) rc = posix_spawn_file_actions_adddup2(&actions, 1, 2);
  if (rc != 0) throw std::runtime_error(std::string("cannot start gnuplot: ") + std::strerror(rc));

  char arg0[] = "gnuplot";
  char arg1[] = "script.gp";
  char* argv[] = {arg0, arg1, nullptr};
  pid_t pid = 0;
  rc = posix_spawnp(&pid, "gnuplot", &actions, nullptr, argv, environ);
  if (rc == ENOENT) throw std::runtime_error(kNotInstalled);
  if (rc != 0) throw std::runtime_error(std::string("cannot start gnuplot: ") + std::strerror(rc));

  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      throw std::runtime_error(std::string("waiting for gnuplot failed: ") + std::strerror(errno));
    }
  }
  return status;
}

}  // namespace

bool gnuplot_available() {
  const char* path_env = std::getenv("PATH");
  if (path_env == nullptr) return false;
  std::istringstream in(path_env);
  std::string dir;
  while (std::getline(in, dir, ':')) {
    if (dir.empty()) dir = ".";
    const std::string exe = dir + "/gnuplot";
    struct stat st {};
    if (::stat(exe.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(exe.c_str(), X_OK) == 0) {
      return true;
    }
  }
  return false;
}

std::string gnuplot_number(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

std::string gnuplot_quote(std::string_view text) {
  std::string out = "'";
  for (char c : text) {
    if (c == '\'') {
      out += "''";
    } else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      out += ' ';
    } else {
      out += c;
    }
  }
  out += '\'';
  return out;
}

void run_gnuplot(const GnuplotJob& job) {
  if (job.outputs.empty()) throw std::invalid_argument("run_gnuplot: the job has no outputs");
  // Check the destinations before doing any work.
  for (const auto& [name, dest] : job.outputs) {
    if (!is_plain_name(name)) {
      throw std::invalid_argument("run_gnuplot: output name '" + name + "' is not a plain file name");
    }
    const fs::path parent = dest.parent_path().empty() ? fs::path(".") : dest.parent_path();
    std::error_code ec;
    if (!fs::is_directory(parent, ec)) {
      throw std::runtime_error("cannot write figure " + dest.string() +
                               ": output directory does not exist: " + parent.string());
    }
  }
  for (const auto& [name, content] : job.data_files) {
    (void)content;
    if (!is_plain_name(name) || name == "script.gp" || name == "gnuplot.log") {
      throw std::invalid_argument("run_gnuplot: data file name '" + name + "' is not allowed");
    }
  }
  if (!gnuplot_available()) throw std::runtime_error(kNotInstalled);

  TempDir tmp;
  for (const auto& [name, content] : job.data_files) write_file(tmp.path() / name, content);
  write_file(tmp.path() / "script.gp", job.script);

  const int status = spawn_gnuplot(tmp.path());
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    const std::string how = WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                              : "killed by signal " + std::to_string(WTERMSIG(status));
    throw std::runtime_error("gnuplot failed (" + how +
                             "): " + first_error_line(read_file(tmp.path() / "gnuplot.log")));
  }

  // Stage every output as DEST.tmp, then rename them all into place.
  std::vector<fs::path> staged;
  auto discard_staged = [&staged] {
    std::error_code ec;
    for (const auto& p : staged) fs::remove(p, ec);
  };
  try {
    for (const auto& [name, dest] : job.outputs) {
      const fs::path produced = tmp.path() / name;
      std::error_code ec;
      const auto size = fs::file_size(produced, ec);
      if (ec || size == 0) {
        throw std::runtime_error("gnuplot did not produce " + name + " (for " + dest.string() +
                                 "): " + first_error_line(read_file(tmp.path() / "gnuplot.log")));
      }
      fs::path staging = dest;
      staging += ".tmp";
      staged.push_back(staging);
      fs::copy_file(produced, staging, fs::copy_options::overwrite_existing);
    }
    for (std::size_t i = 0; i < staged.size(); ++i) fs::rename(staged[i], job.outputs[i].second);
  } catch (const fs::filesystem_error& e) {
    discard_staged();
    throw std::runtime_error(std::string("cannot move figure into place: ") + e.what());
  } catch (...) {
    discard_staged();
    throw;
  }
}

void render_png_svg(const std::filesystem::path& stem,
                    std::vector<std::pair<std::string, std::string>> data_files, const std::string& body,
                    int width_px, int height_px) {
  if (stem.filename().empty()) {
    throw std::invalid_argument("figure output stem '" + stem.string() + "' has no file name");
  }
  const std::string size = std::to_string(width_px) + "," + std::to_string(height_px);
  std::string script = "set encoding utf8\n";
  script += "set terminal pngcairo size " + size + " noenhanced font 'DejaVu Sans,11' background rgb 'white'\n";
  script += "set output 'figure.png'\n" + body + "\n";
  script += "set terminal svg size " + size + " noenhanced font 'DejaVu Sans,12' background rgb 'white'\n";
  script += "set output 'figure.svg'\n" + body + "\nunset output\n";

  std::filesystem::path png = stem, svg = stem;
  png += ".png";
  svg += ".svg";
  GnuplotJob job;
  job.data_files = std::move(data_files);
  job.script = std::move(script);
  job.outputs = {{"figure.png", png}, {"figure.svg", svg}};
  run_gnuplot(job);
}

std::string series_colour(int i) {
  static const char* const kPalette[] = {"#4E79A7", "#F28E2B", "#59A14F", "#E15759", "#B07AA1",
                                         "#76B7B2", "#EDC948", "#FF9DA7", "#9C755F", "#BAB0AC"};
  constexpr int kSize = static_cast<int>(sizeof(kPalette) / sizeof(kPalette[0]));
  if (i < 0) return "#000000";
  return kPalette[i % kSize];
}

std::pair<double, double> stacked_panel_span(std::size_t p, std::size_t n) {
  constexpr double kTop = 0.90, kBottom = 0.10, kGap = 0.07;
  const double h = (kTop - kBottom - kGap * static_cast<double>(n - 1)) / static_cast<double>(n);
  const double top = kTop - static_cast<double>(p) * (h + kGap);
  return {top, top - h};
}

}  // namespace odotune::results
