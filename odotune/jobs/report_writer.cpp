#include <odotune/jobs/report_writer.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>

namespace odotune::jobs {

std::string file_safe(const std::string& s) {
  std::string out;
  for (char c : s)
    out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.') ? c : '_';
  return out;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (auto& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string seeds_phrase(const std::vector<results::RunRecord>& runs) {
  std::vector<std::uint64_t> seeds;
  for (const auto& r : runs)
    if (std::find(seeds.begin(), seeds.end(), r.seed) == seeds.end()) seeds.push_back(r.seed);
  return seeds.size() == 1 ? "1 seed" : fmt::format("mean over {} seeds", seeds.size());
}

void ReportWriter::text(const std::string& name, const std::string& what, const std::string& content) {
  const std::filesystem::path p = dir_ / name;
  try {
    core::write_atomically(p, what, content);
  } catch (const std::exception& ex) {
    throw core::Failure(ex.what());
  }
  files.push_back(p);
}

std::vector<std::filesystem::path> ReportWriter::finish(results::HtmlPage& page,
                                                        const std::vector<std::string>& notes) {
  for (const std::string& n : notes) page.paragraph("Note: " + n + ".");
  text("index.html", "report page", page.html());
  return std::move(files);
}

std::string ReportWriter::svg_of(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace odotune::jobs
