// The report's numbers from hand-made runs whose means are worked out here,
// and the HTML page's SVG inlining.
#include <odotune/results/report_tables.h>

#include <gtest/gtest.h>

#include <cmath>

#include <odotune/results/report_html.h>

namespace odotune::results {
namespace {

RunRecord run(const std::string& model, const std::string& track, int mode, std::uint64_t seed,
              double baseline_rmse_m, double tuned_rmse_m, const std::string& heldout = "") {
  RunRecord r;
  r.model = model;
  r.track = heldout.empty() ? track : "all-but-" + heldout;
  r.heldout_track = heldout;
  r.mode = mode;
  r.seed = seed;
  r.baseline = {baseline_rmse_m, 2 * baseline_rmse_m, 4 * baseline_rmse_m};
  r.tuned = {tuned_rmse_m, 2 * tuned_rmse_m, 3 * tuned_rmse_m};
  return r;
}

std::vector<RunRecord> sample_runs() {
  return {
      run("alpha", "t2", 7, 1, 0.100, 0.050),   // +50 %
      run("alpha", "t2", 7, 2, 0.100, 0.070),   // +30 %
      run("rq", "t2", 7, 1, 0.100, 0.080),      // +20 %
      run("rq", "t1", 1, 1, 0.200, 0.100),      // +50 %
      run("rq", "t1", 7, 1, 0.200, 0.300),      // −50 %
      run("rq", "", 7, 1, 0.100, 0.090, "t2"),  // held out, +10 %
      run("rq", "", 7, 2, 0.100, 0.070, "t2"),  // held out, +30 %
  };
}

TEST(ReportTables, ModelsAndTracksComeInReportOrder) {
  const auto runs = sample_runs();
  EXPECT_EQ(report_models(runs), (std::vector<std::string>{"rq", "alpha"}));
  EXPECT_EQ(report_tracks(runs), (std::vector<std::string>{"t2", "t1"}));
  EXPECT_EQ(report_modes(runs), (std::vector<int>{1, 7}));
}

TEST(ReportTables, ImprovementGridIsTheMeanOverSeedsPerModeAndTrack) {
  const auto runs = sample_runs();
  const std::vector<std::string> tracks = {"t1", "t2"};
  const auto alpha = improvement_grid(runs, "alpha", ReportMetric::rmse, false, tracks);
  ASSERT_EQ(alpha.mean_pct.size(), 7u);
  EXPECT_NEAR(alpha.mean_pct[6][1], 40.0, 1e-9);  // (50 + 30) / 2
  EXPECT_EQ(alpha.runs[6][1], 2);
  EXPECT_TRUE(std::isnan(alpha.mean_pct[6][0]));  // alpha has no t1 run
  EXPECT_TRUE(std::isnan(alpha.mean_pct[0][1]));
  const auto rq = improvement_grid(runs, "rq", ReportMetric::rmse, false, tracks);
  EXPECT_NEAR(rq.mean_pct[0][0], 50.0, 1e-9);
  EXPECT_NEAR(rq.mean_pct[6][0], -50.0, 1e-9);
  EXPECT_NEAR(rq.mean_pct[6][1], 20.0, 1e-9);  // held-out runs are not mixed in
  // MAXE: baseline 4·b, tuned 3·t.
  const auto maxe = improvement_grid(runs, "rq", ReportMetric::maxe, false, tracks);
  EXPECT_NEAR(maxe.mean_pct[6][1], 100.0 * (0.4 - 0.24) / 0.4, 1e-9);
  const auto held = improvement_grid(runs, "rq", ReportMetric::rmse, true, tracks);
  EXPECT_NEAR(held.mean_pct[6][1], 20.0, 1e-9);  // (10 + 30) / 2
  EXPECT_FALSE(held.empty());
  EXPECT_TRUE(improvement_grid(runs, "alpha", ReportMetric::rmse, true, tracks).empty());
}

TEST(ReportTables, Table1HasOriginalAndMeanTunedRmsePerTrackAndMode) {
  const RmseTable t = rmse_table(sample_runs());
  EXPECT_EQ(t.models, (std::vector<std::string>{"rq", "alpha"}));
  ASSERT_EQ(t.rows.size(), 3u);  // t2/7, t1/1, t1/7 (held-out runs excluded)
  EXPECT_EQ(t.rows[0].track, "t2");
  EXPECT_EQ(t.rows[0].mode, 7);
  EXPECT_NEAR(t.rows[0].original_m, 0.100, 1e-12);
  EXPECT_NEAR(t.rows[0].tuned_m[0], 0.080, 1e-12);
  EXPECT_NEAR(t.rows[0].tuned_m[1], 0.060, 1e-12);
  EXPECT_EQ(t.rows[1].track, "t1");
  EXPECT_TRUE(std::isnan(t.rows[1].tuned_m[1]));

  const std::string csv = to_csv(t);
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "track,mode,original_mm,rq_mm,alpha_mm");
  EXPECT_NE(csv.find("\nt2,7,100.00,80.00,60.00\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\nt1,1,200.00,100.00,\n"), std::string::npos) << csv;

  const std::string md = to_markdown(text_table(t));
  EXPECT_NE(md.find("| t2 | 7 | 100.00 | 80.00 | **60.00** |"), std::string::npos) << md;
  EXPECT_NE(md.find("| t1 | 1 | 200.00 | **100.00** | – |"), std::string::npos) << md;
  // Lower error is better: a tuned value worse than the original is not the
  // row's best, the original is.
  EXPECT_NE(md.find("| t1 | 7 | **200.00** | 300.00 | – |"), std::string::npos) << md;
  EXPECT_NE(md.find("|---|---:|---:|---:|---:|"), std::string::npos) << md;
}

TEST(ReportTables, SeedSpreadIsMinMedianMaxOverAModelsSeeds) {
  auto runs = sample_runs();
  runs.push_back(run("alpha", "t2", 7, 3, 0.100, 0.120));  // -20 %
  const auto rows = seed_spread(runs, "alpha");
  ASSERT_EQ(rows.size(), 1u);  // rq's runs and held-out runs are not mixed in
  EXPECT_EQ(rows[0].track, "t2");
  EXPECT_EQ(rows[0].mode, 7);
  EXPECT_EQ(rows[0].runs, 3);
  EXPECT_NEAR(rows[0].improvement_min_pct, -20.0, 1e-9);
  EXPECT_NEAR(rows[0].improvement_median_pct, 30.0, 1e-9);
  EXPECT_NEAR(rows[0].improvement_max_pct, 50.0, 1e-9);
  EXPECT_NEAR(rows[0].tuned_min_m, 0.050, 1e-12);
  EXPECT_NEAR(rows[0].tuned_median_m, 0.070, 1e-12);
  EXPECT_NEAR(rows[0].tuned_max_m, 0.120, 1e-12);
  const auto rq = seed_spread(runs, "rq");
  ASSERT_EQ(rq.size(), 3u);  // t2/7, t1/1, t1/7
  EXPECT_NEAR(rq[2].improvement_median_pct, -50.0, 1e-9);
  const std::string md = to_markdown(text_table(rows, [](int m) { return "mode " + std::to_string(m); }));
  EXPECT_NE(md.find("| t2 | mode 7 | 3 | -20.0 % | +30.0 % | +50.0 % | 50.00 | 70.00 | 120.00 |"),
            std::string::npos)
      << md;
}

TEST(ReportTables, ParamRangeTextSaysWhatTheRecordingDetermined) {
  EXPECT_EQ(param_range_text(1.8412, {0.91234, 3.2, true}), "1.84 [0.912, 3.2]");
  EXPECT_EQ(param_range_text(1.0, {0.01, 100.0, false}), "1, not determined by this recording [0.01, 100]");
}

TEST(ReportTables, GeneralisationPutsPerTrackAndHeldOutSideBySide) {
  const auto rows = generalisation(sample_runs(), ReportMetric::rmse);
  ASSERT_EQ(rows.size(), 1u);  // only rq on t2 has both kinds
  EXPECT_EQ(rows[0].model, "rq");
  EXPECT_EQ(rows[0].track, "t2");
  EXPECT_NEAR(rows[0].per_track_pct, 20.0, 1e-9);
  EXPECT_NEAR(rows[0].heldout_pct, 20.0, 1e-9);
  EXPECT_EQ(rows[0].per_track_runs, 1);
  EXPECT_EQ(rows[0].heldout_runs, 2);
  const std::string md = to_markdown(text_table(rows, ReportMetric::rmse));
  EXPECT_NE(md.find("| rq | t2 | +20.0 % | +20.0 % | 1 + 2 |"), std::string::npos) << md;
}

TEST(ReportHtml, InlinedSvgDropsThePrologAndPrefixesEveryId) {
  const std::string svg = "<?xml version=\"1.0\"?>\n<!DOCTYPE svg>\n<svg width=\"10\">"
                          "<filter id='textbox'/><path id=\"gpPt0\"/><use xlink:href=\"#gpPt0\"/>"
                          "<text filter='url(#textbox)'>x_y</text></svg>\n";
  const std::string out = inline_svg(svg, "f3-");
  EXPECT_EQ(out.rfind("<svg", 0), 0u) << out;
  EXPECT_EQ(out.find("<?xml"), std::string::npos);
  EXPECT_NE(out.find("id='f3-textbox'"), std::string::npos) << out;
  EXPECT_NE(out.find("id=\"f3-gpPt0\""), std::string::npos) << out;
  EXPECT_NE(out.find("href=\"#f3-gpPt0\""), std::string::npos) << out;
  EXPECT_NE(out.find("url(#f3-textbox)"), std::string::npos) << out;
  EXPECT_EQ(out.substr(out.size() - 6), "</svg>");
  EXPECT_THROW(inline_svg("<html></html>", "f-"), std::invalid_argument);
}

TEST(ReportHtml, PageEscapesTextAndKeepsTablesAndFigures) {
  HtmlPage page("a <b> & c");
  page.paragraph("x < y **bold**");
  page.figures({{"cap \"1\"", "<svg><path id='p'/></svg>", "f.png", ""},
                {"cap 2", "<svg><path id='p'/></svg>", "", ""}});
  page.table(text_table(rmse_table(sample_runs())));
  const std::string html = page.html();
  EXPECT_NE(html.find("<title>a &lt;b&gt; &amp; c</title>"), std::string::npos);
  EXPECT_NE(html.find("x &lt; y <strong>bold</strong>"), std::string::npos);
  EXPECT_NE(html.find("id='f0-p'"), std::string::npos);
  EXPECT_NE(html.find("id='f1-p'"), std::string::npos);
  EXPECT_NE(html.find("cap &quot;1&quot; (<a href=\"f.png\">PNG</a>)"), std::string::npos);
  EXPECT_NE(html.find("<td class=\"num\"><strong>60.00</strong></td>"), std::string::npos) << html;
  EXPECT_EQ(html.find("<script"), std::string::npos);
}

}  // namespace
}  // namespace odotune::results
