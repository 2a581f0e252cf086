#include <odotune/results/report_html.h>

#include <regex>
#include <stdexcept>

#include <fmt/format.h>

namespace odotune::results {

namespace {
// "**x**" → <strong>x</strong> in already-escaped text.
std::string emphasis(const std::string& escaped) {
  static const std::regex bold(R"(\*\*([^*]+)\*\*)");
  return std::regex_replace(escaped, bold, "<strong>$1</strong>");
}
}  // namespace

std::string html_escape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string inline_svg(const std::string& svg_text, const std::string& id_prefix) {
  const auto begin = svg_text.find("<svg");
  const auto end = svg_text.rfind("</svg>");
  if (begin == std::string::npos || end == std::string::npos || end < begin)
    throw std::invalid_argument("inline_svg: no <svg> element in the figure");
  std::string svg = svg_text.substr(begin, end + 6 - begin);
  // gnuplot's ids are plain names (gnuplot_canvas, gpPt0, gpDot, …); a
  // regex over the three reference forms is enough for them.
  static const std::regex id(R"re(\bid=(["'])([^"']+)\1)re");
  static const std::regex href(R"re(href=(["'])#([^"']+)\1)re");
  static const std::regex url(R"re(url\(#([^)]+)\))re");
  svg = std::regex_replace(svg, id, "id=$1" + id_prefix + "$2$1");
  svg = std::regex_replace(svg, href, "href=$1#" + id_prefix + "$2$1");
  svg = std::regex_replace(svg, url, "url(#" + id_prefix + "$1)");
  return svg;
}

HtmlPage::HtmlPage(std::string title) : title_(std::move(title)) {}

void HtmlPage::heading(const std::string& text) { body_ += fmt::format("<h2>{}</h2>\n", html_escape(text)); }

void HtmlPage::paragraph(const std::string& text) {
  body_ += fmt::format("<p>{}</p>\n", emphasis(html_escape(text)));
}

void HtmlPage::figures(const std::vector<HtmlFigure>& figs) {
  body_ += "<div class=\"row\">\n";
  for (const auto& f : figs) {
    const std::string prefix = f.id_prefix.empty() ? fmt::format("f{}-", next_figure_) : f.id_prefix;
    ++next_figure_;
    body_ += "<figure>\n" + inline_svg(f.svg_text, prefix) + "\n<figcaption>" + html_escape(f.caption);
    if (!f.png_href.empty()) body_ += fmt::format(" (<a href=\"{}\">PNG</a>)", html_escape(f.png_href));
    body_ += "</figcaption>\n</figure>\n";
  }
  body_ += "</div>\n";
}

void HtmlPage::table(const TextTable& t) {
  auto align = [&t](std::size_t i) { return i < t.numeric.size() && t.numeric[i] ? " class=\"num\"" : ""; };
  body_ += "<table>\n<thead><tr>";
  for (std::size_t i = 0; i < t.header.size(); ++i)
    body_ += fmt::format("<th{}>{}</th>", align(i), html_escape(t.header[i]));
  body_ += "</tr></thead>\n<tbody>\n";
  for (const auto& row : t.rows) {
    body_ += "<tr>";
    for (std::size_t i = 0; i < row.size(); ++i)
      body_ += fmt::format("<td{}>{}</td>", align(i), emphasis(html_escape(row[i])));
    body_ += "</tr>\n";
  }
  body_ += "</tbody>\n</table>\n";
}

void HtmlPage::list(const std::vector<std::string>& items) {
  body_ += "<ul>\n";
  for (const auto& item : items) body_ += "<li>" + html_escape(item) + "</li>\n";
  body_ += "</ul>\n";
}

void HtmlPage::preformatted(const std::string& text) { body_ += "<pre>" + html_escape(text) + "</pre>\n"; }

std::string HtmlPage::html() const {
  return fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<title>{0}</title>\n<style>\n"
      "body {{ font-family: sans-serif; margin: 2em; color: #222; }}\n"
      ".row {{ display: flex; flex-wrap: wrap; gap: 1.5em; }}\n"
      "figure {{ margin: 0; }} figure svg {{ max-width: 100%; height: auto; }}\n"
      "figcaption {{ font-size: 0.9em; color: #555; max-width: 40em; }}\n"
      "table {{ border-collapse: collapse; margin: 1em 0; }}\n"
      "th, td {{ border: 1px solid #ccc; padding: 0.25em 0.6em; }}\n"
      "th {{ background: #f2f2f2; }} td.num, th.num {{ text-align: right; }}\n"
      "pre {{ background: #f6f6f6; border: 1px solid #ddd; padding: 0.8em; overflow-x: auto; }}\n"
      "</style>\n</head>\n<body>\n<h1>{0}</h1>\n{1}</body>\n</html>\n",
      html_escape(title_), body_);
}

}  // namespace odotune::results
