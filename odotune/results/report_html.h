// The report as one self-contained HTML page: figures are inlined as SVG
// (no external files, no scripts), tables are HTML tables. Builds text only;
// the caller writes it (atomically).
#pragma once

#include <string>
#include <vector>

#include <odotune/results/report_tables.h>

namespace odotune::results {

// An SVG document made embeddable in HTML: the XML prolog and DOCTYPE are
// dropped and every id (and every reference to it: href="#id",
// xlink:href="#id", url(#id)) gets `id_prefix`, so several gnuplot figures
// on one page do not share ids. Throws std::invalid_argument when there is
// no <svg …>…</svg> element.
std::string inline_svg(const std::string& svg_text, const std::string& id_prefix);

// Escapes &, <, >, " for HTML text and attributes.
std::string html_escape(const std::string& text);

struct HtmlFigure {
  std::string caption;
  std::string svg_text;   // the figure's SVG file, verbatim
  std::string png_href;   // relative link to the PNG version (may be empty)
  std::string id_prefix;  // prefix of the figure's SVG ids ("" = "f<n>-", n counting figures)
};

class HtmlPage {
 public:
  explicit HtmlPage(std::string title);
  void heading(const std::string& text);    // a section heading
  void paragraph(const std::string& text);  // escaped; "**x**" emphasised
  // Figures side by side (wrapping on narrow screens), each with its caption.
  void figures(const std::vector<HtmlFigure>& figs);
  void table(const TextTable& t);
  void list(const std::vector<std::string>& items);  // a bulleted list, escaped
  void preformatted(const std::string& text);        // a <pre> block, escaped
  // The complete document.
  std::string html() const;

 private:
  std::string title_;
  std::string body_;
  int next_figure_ = 0;
};

}  // namespace odotune::results
