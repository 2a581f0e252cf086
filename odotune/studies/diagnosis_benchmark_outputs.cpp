#include <odotune/studies/diagnosis_benchmark_outputs.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <fmt/format.h>

#include <odotune/core/atomic_file.h>
#include <odotune/core/failure.h>
#include <odotune/results/gnuplot.h>

namespace odotune::studies {

namespace {
namespace fs = std::filesystem;

// RFC 4180 cell: quoted when it holds a comma, quote or line break.
std::string cell(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string g(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : ""; }

std::string joined(const std::vector<std::string>& v, const char* sep = "; ") {
  std::string out;
  for (const std::string& s : v) out += (out.empty() ? "" : sep) + s;
  return out;
}

std::vector<std::string> names(const std::vector<diagnose::Effect>& effects) {
  std::vector<std::string> out;
  for (diagnose::Effect e : effects) out.emplace_back(diagnose::effect_name(e));
  return out;
}

std::string percent(double share) {
  return std::isfinite(share) ? fmt::format("{:.1f} %", 100.0 * share) : "n/a";
}

std::string rate_cell(const Rate& r) {
  return fmt::format("{}/{} ({})", r.passed, r.cases, percent(r.share()));
}

// Pass rate of the cases for which key(case) == each value, in first-seen order.
template <class Key>
std::string breakdown(const std::vector<CaseResult>& cases, const std::string& title, Key key) {
  std::vector<std::string> order;
  std::map<std::string, Rate> rates;
  for (const CaseResult& r : cases) {
    if (r.grade.category == CaseCategory::undetectable) continue;
    const std::string k = key(r);
    if (!rates.count(k)) order.push_back(k);
    ++rates[k].cases;
    rates[k].passed += r.grade.pass ? 1 : 0;
  }
  std::sort(order.begin(), order.end());
  std::string md = fmt::format("| {} | right (null, single and two-effect cases) |\n|---|---|\n", title);
  for (const std::string& k : order) md += fmt::format("| {} | {} |\n", k, rate_cell(rates[k]));
  return md;
}

// "1", or for a multi-recording case "3 (1 held out)".
std::string recordings_text(const DiagnosisCase& c) {
  return c.multi() ? fmt::format("{} ({} held out)", c.recordings.size(), c.heldout_recordings()) : "1";
}

// "| what | right | aim | verdict |" for a rate and its least share right
// (NaN: no aim).
std::string aim_row(const std::string& what, const Rate& r, double least) {
  if (!std::isfinite(least)) return fmt::format("| {} | {} | none | |\n", what, rate_cell(r));
  const std::string verdict = r.cases == 0 ? "n/a (no cases)" : r.share() >= least ? "met" : "**not met**";
  return fmt::format("| {} | {} | >= {:.0f} % | {} |\n", what, rate_cell(r), 100.0 * least, verdict);
}

// The aims table's rows of one kind of case (`prefix` names the kind).
std::string aims_rows(const CategoryRates& c, const std::string& prefix) {
  std::string md;
  for (const auto b : {MarginBucket::from_3, MarginBucket::from_1_5_to_3, MarginBucket::under_1_5}) {
    const auto k = static_cast<std::size_t>(b);
    md += aim_row(fmt::format("{}single effect, {}", prefix, to_string(b)), c.single_by_margin[k],
                  kSingleEffectAims[k]);
    md += aim_row(fmt::format("{}two effects, {}", prefix, to_string(b)), c.two_by_margin[k],
                  kTwoEffectAims[k]);
  }
  const double share = c.null_finding_share();
  const std::string verdict = !std::isfinite(share)      ? "n/a (no cases)"
                              : share <= kNullFindingAim ? "met"
                                                         : "**not met**";
  md += fmt::format("| {}null cases with any finding | {}/{} ({}) | <= {:.0f} % | {} |\n", prefix,
                    c.null_with_finding, c.null_cases.cases, percent(share), 100.0 * kNullFindingAim, verdict);
  md += fmt::format("| {}null: right (no finding, not refused) | {} | | |\n", prefix, rate_cell(c.null_cases));
  md += fmt::format("| {}single effect, any margin | {} | | |\n", prefix, rate_cell(c.single));
  md += fmt::format("| {}two effects, any margin | {} | | |\n", prefix, rate_cell(c.two));
  md += fmt::format("| {}effects simulated, none detectable: nothing wrong named | {} | | |\n", prefix,
                    rate_cell(c.undetectable));
  return md;
}

void confusion_figure(const Confusion& c, const fs::path& stem, int cases) {
  // Cells: x = named column, y = true row, colour = share of the row's counts.
  std::string cells, dark, light;
  for (std::size_t r = 0; r < c.rows.size(); ++r) {
    int row_total = 0;
    for (int v : c.counts[r]) row_total += v;
    for (std::size_t k = 0; k < c.cols.size(); ++k) {
      const int v = c.counts[r][k];
      if (v == 0) continue;
      const double share = row_total > 0 ? static_cast<double>(v) / row_total : 0.0;
      const std::string xy = fmt::format("{} {}", k, r);
      cells += fmt::format("{} {}\n", xy, results::gnuplot_number(share));
      (share > 0.6 ? light : dark) += fmt::format("{} \"{}\"\n", xy, v);
    }
  }
  auto tics = [](const std::vector<std::string>& names) {
    std::string s = "(";
    for (std::size_t i = 0; i < names.size(); ++i)
      s += fmt::format("{}{} {}", i ? ", " : "", results::gnuplot_quote(names[i]), i);
    return s + ")";
  };
  std::string body;
  body += "set title " +
          results::gnuplot_quote(fmt::format("Diagnosis benchmark: true vs named effects ({} cases)", cases)) +
          " font ',13'\n";
  body += "set xlabel 'named by the diagnosis'\nset ylabel 'true (detectable) effect'\n";
  body += "set cblabel 'share of the row'\n";
  body += fmt::format("set xrange [-0.5:{}.5]\nset yrange [{}.5:-0.5]\n", c.cols.size() - 1, c.rows.size() - 1);
  body += "set xtics " + tics(c.cols) + " scale 0 rotate by 35 right\n";
  body += "set ytics " + tics(c.rows) + " scale 0\n";
  body += "set palette defined (0 '#f7fbff', 0.5 '#6baed6', 1 '#08306b')\nset cbrange [0:1]\nset colorbox\n";
  body += "unset key\nset border 0\nset style fill solid 1.0 noborder\n";
  body += "set grid front noxtics noytics\n";
  std::string plot = cells.empty()
                         ? "plot NaN with points lc palette notitle"
                         : "plot 'cells.dat' using 1:2:(0.5):(0.5):3 with boxxyerror fc palette notitle";
  if (!dark.empty()) plot += ", 'dark.dat' using 1:2:3 with labels tc rgb 'black' notitle";
  if (!light.empty()) plot += ", 'light.dat' using 1:2:3 with labels tc rgb 'white' notitle";
  body += plot + "\n";
  results::render_png_svg(stem, {{"cells.dat", cells}, {"dark.dat", dark}, {"light.dat", light}}, body, 1100,
                          820);
}

// summary.md's "Against the aims": the aims table of each kind of case.
std::string aims_section(const DiagnosisBenchmark& b) {
  const BenchmarkSummary& s = b.summary;
  std::string md;
  md += "## Against the aims\n\nBy margin: the smallest true gain of a case's detectable effects over its "
        "floor (\"By margin\" below; docs/diagnosis/benchmark.md, \"Aims\"). Under 1.5 floors is reported "
        "with no aim.\n\n| cases | right | aim | verdict |\n|---|---|---|---|\n";
  md += aims_rows(s.single_recording, "");
  const bool any_multi = std::any_of(b.cases.begin(), b.cases.end(),
                                     [](const CaseResult& r) { return r.c.multi(); });
  if (b.options.draw.multi_share > 0.0 || any_multi) md += aims_rows(s.multi_recording, "multi-recording: ");
  md += fmt::format("| all | {} | | |\n\n", rate_cell(s.all));
  return md;
}

}  // namespace

std::string cases_csv(const DiagnosisBenchmark& b) {
  std::string s =
      "case,case_seed,category,recordings,heldout_recordings,pass,why,robot,drive,duration_s,track_rows,odometry,commands_alongside,"
      "odo_rate_hz,gyro_rate_hz,gyro_sigma_rad_s,reference,gt_rate_hz,gt_sigma_m,gt_sigma_rad,fix_rate_hz,"
      "fix_sigma_m,ref_sigma_m,true_effects,detectable,tolerated,gain_over_floor_m,nominal_heldout_m,"
      "findings,heldout_before_m,heldout_after_m,param_errors,simulate_s,truth_s,diagnose_s,truth_note\n";
  for (const CaseResult& r : b.cases) {
    const DiagnosisCase& c = r.c;
    std::vector<std::string> gains, found, perr;
    for (const EffectTruth& t : r.truth.effects)
      gains.push_back(
          fmt::format("{}: {} / {}{}{}", t.effect.name(), g(t.gain_m), g(t.floor_m),
                      std::isfinite(t.heading_floor_rad)
                          ? fmt::format(" heading {} / {} rad", g(t.heading_gain_rad), g(t.heading_floor_rad))
                          : "",
                      t.on_all_windows ? " (all windows)" : ""));
    for (const CaseFinding& f : r.findings)
      found.push_back(f.spec.empty() ? std::string(diagnose::to_string(f.kind)) : f.spec);
    for (const ParamCheck& p : r.grade.params)
      if (p.graded)
        perr.push_back(fmt::format("{}.{}={}", diagnose::effect_name(p.effect), p.param, g(p.normalised)));
    const std::vector<std::string> row = {std::to_string(c.index),
                                          std::to_string(c.seed),
                                          std::string(to_string(r.grade.category)),
                                          std::to_string(c.multi() ? c.recordings.size() : 1),
                                          std::to_string(c.heldout_recordings()),
                                          r.grade.pass ? "1" : "0",
                                          r.grade.why,
                                          c.robot,
                                          c.drive,
                                          g(r.track_duration_s),
                                          std::to_string(r.track_rows),
                                          std::string(to_string(c.odometry)),
                                          c.commands_alongside ? "1" : "0",
                                          g(c.odo_rate_hz),
                                          g(c.gyro_rate_hz),
                                          g(c.gyro_sigma_rad_s),
                                          std::string(to_string(c.reference)),
                                          g(c.gt_rate_hz),
                                          g(c.gt_sigma_m),
                                          g(c.gt_sigma_rad),
                                          g(c.fix_rate_hz),
                                          g(c.fix_sigma_m),
                                          g(r.truth.ref_sigma_m),
                                          c.effects_text(),
                                          joined(names(r.grade.expected)),
                                          joined(names(r.grade.tolerated)),
                                          joined(gains),
                                          g(r.truth.nominal_heldout_m),
                                          found.empty() ? "none" : joined(found),
                                          g(r.grade.heldout_before_m),
                                          g(r.grade.heldout_after_m),
                                          joined(perr),
                                          fmt::format("{:.3f}", r.simulate_s),
                                          fmt::format("{:.3f}", r.truth_s),
                                          fmt::format("{:.3f}", r.diagnose_s),
                                          r.truth_note};
    for (std::size_t i = 0; i < row.size(); ++i) s += (i ? "," : "") + cell(row[i]);
    s += "\n";
  }
  return s;
}

std::string confusion_csv(const Confusion& c) {
  std::string s = "true\\named";
  for (const std::string& col : c.cols) s += "," + col;
  s += "\n";
  for (std::size_t r = 0; r < c.rows.size(); ++r) {
    s += c.rows[r];
    for (int v : c.counts[r]) s += fmt::format(",{}", v);
    s += "\n";
  }
  return s;
}

namespace {

// The title and the run's settings.
std::string intro_section(const DiagnosisBenchmark& b, const std::string& command) {
  const DiagnosisBenchmarkOptions& o = b.options;
  std::string md = "# Diagnosis benchmark\n\n";
  md += fmt::format(
      "`{}`\n\n{} random cases ({}..{}) of seed {}: drives of {:g}-{:g} min, rates up to {:g} Hz, "
      "{:.0f} % null and {:.0f} % two-effect draws, {:.0f} % multi-recording cases; {} threads, {:.0f} s in "
      "all. Method and grading: docs/diagnosis/benchmark.md.\n\n",
      command, o.cases, o.first, o.first + o.cases - 1, o.seed, o.draw.min_minutes, o.draw.max_minutes,
      o.draw.max_rate_hz, 100.0 * o.draw.null_share, 100.0 * o.draw.two_share, 100.0 * o.draw.multi_share,
      b.threads_used, b.wall_s);
  return md;
}

// Failures by kind and the per-effect table.
std::string failures_and_effects_sections(const BenchmarkSummary& s) {
  std::string md =
      "## Failures by kind\n\nA failed case may count under several kinds.\n\n| kind | cases |\n|---|---|\n";
  for (const auto& [kind, n] : s.failures) md += fmt::format("| {} | {} |\n", kind, n);

  md += "\n## Per effect\n\nrecall: named when detectable; precision: detectable when named (tolerated, "
        "i.e. true but undetectable, namings left out); right: the case passed.\n\n"
        "| effect | detectable in | recall | precision | right |\n|---|---|---|---|---|\n";
  for (const EffectScore& e : s.effects)
    md += fmt::format("| {} | {} | {} | {} | {} |\n", diagnose::to_string(e.effect), e.expected,
                      percent(e.recall()), percent(e.precision()),
                      e.expected > 0 ? percent(static_cast<double>(e.right) / e.expected) : "n/a");
  return md;
}

// The confusion matrix, rows and columns that hold nothing left out.
std::string confusion_section(const Confusion& c) {
  std::string md =
      "\n## Confusion matrix\n\nRows: true detectable effects (none: nothing detectable); columns: what "
      "the diagnosis named (none: nothing wrong). confusion.csv, confusion.png.\n\n| true \\ named |";
  std::vector<std::size_t> used_cols;
  for (std::size_t k = 0; k < c.cols.size(); ++k) {
    int total = 0;
    for (const auto& row : c.counts) total += row[k];
    if (total > 0) used_cols.push_back(k);
  }
  for (std::size_t k : used_cols) md += " " + c.cols[k] + " |";
  md += "\n|---|";
  for (std::size_t i = 0; i < used_cols.size(); ++i) md += "---|";
  md += "\n";
  for (std::size_t r = 0; r < c.rows.size(); ++r) {
    int total = 0;
    for (int v : c.counts[r]) total += v;
    if (total == 0) continue;
    md += "| " + c.rows[r] + " |";
    for (std::size_t k : used_cols) md += c.counts[r][k] ? fmt::format(" {} |", c.counts[r][k]) : " |";
    md += "\n";
  }
  return md;
}

// Parameter errors and the time per case.
std::string params_and_time_sections(const DiagnosisBenchmark& b) {
  const BenchmarkSummary& s = b.summary;
  std::string md =
      "\n## Parameter errors\n\nNormalised error = (found − truth) / (tolerance / 0.25), i.e. relative to "
      "the parameter's departure from its no-op value (radius_step.t: error / 20 s; slip_zone.box: the "
      "path rule's larger miss share); within tolerance means |error| <= 25 %.\n\n"
      "| parameter | n | within | median | 90 % | max |\n|---|---|---|---|---|---|\n";
  for (const ParamStats& p : s.params)
    md += fmt::format("| {} | {} | {} | {} | {} | {} |\n", p.name, p.n, p.within, percent(p.median_abs),
                      percent(p.p90_abs), percent(p.max_abs));

  md += fmt::format(
      "\n## Time per case\n\nSimulation, detectability and diagnosis: mean {:.1f} s, median {:.1f} s, "
      "max {:.1f} s; the diagnosis alone: mean {:.1f} s ({} threads sharing the machine).\n\n",
      s.time_mean_s, s.time_median_s, s.time_max_s, s.diagnose_mean_s, b.threads_used);
  return md;
}

// The pass rates by margin, reference shape, odometry and recordings.
std::string breakdown_sections(const DiagnosisBenchmark& b) {
  std::string md =
      "## By margin\n\nThe smallest margin of a case's detectable effects: its true gain over its floor (the "
      "larger of position and heading), as the truth measures it with the true parameters; near 1 a "
      "fitted model recovers about half the time.\n\n";
  md += breakdown(b.cases, "category, margin", [](const CaseResult& r) {
    const char* kind = r.c.multi() ? "multi " : "";
    if (r.grade.category == CaseCategory::null_case) return fmt::format("{}null", kind);
    return fmt::format("{}{}, {}", kind, to_string(r.grade.category),
                       to_string(margin_bucket(case_margin(r.truth))));
  });
  md += "\n## By reference shape and odometry\n\n";
  md += breakdown(b.cases, "reference",
                  [](const CaseResult& r) { return std::string(to_string(r.c.reference)); });
  md += "\n";
  md += breakdown(b.cases, "odometry",
                  [](const CaseResult& r) { return std::string(to_string(r.c.odometry)); });
  md += "\n";
  md += breakdown(b.cases, "recordings", [](const CaseResult& r) {
    if (!r.c.multi()) return std::string("1");
    return fmt::format("{} ({} held out)", r.c.recordings.size(), r.c.heldout_recordings());
  });
  return md;
}

// The failed cases, with how to re-run one alone.
std::string failed_cases_section(const DiagnosisBenchmark& b) {
  std::string md =
      "\n## Failed cases\n\nRe-run one alone: `odotune study diagnosis --seed S --first I --cases 1 "
      "--keep-tracks --out DIR`, then `odotune diagnose DIR/tracks/case_IIII.csv` (a multi-recording case: "
      "`odotune diagnose DIR/tracks/case_IIII_r1.csv ... --heldout DIR/tracks/case_IIII_rN.csv`, the held-out "
      "recordings last).\n\n"
      "| case | category | recordings | true effects | named | why |\n|---|---|---|---|---|---|\n";
  for (const CaseResult& r : b.cases) {
    if (r.grade.pass) continue;
    std::vector<std::string> found;
    for (const CaseFinding& f : r.findings)
      found.push_back(f.spec.empty() ? std::string(diagnose::to_string(f.kind)) : f.spec);
    std::string why = r.grade.why;
    std::replace(why.begin(), why.end(), '|', '/');
    md += fmt::format("| {} | {} | {} | {} | {} | {} |\n", r.c.index, to_string(r.grade.category),
                      recordings_text(r.c), r.c.effects_text(), found.empty() ? "none" : joined(found), why);
  }
  return md;
}

}  // namespace

std::string benchmark_summary_markdown(const DiagnosisBenchmark& b, const std::string& command) {
  std::string md = intro_section(b, command);
  md += aims_section(b);
  md += fmt::format("Refused tracks: {} (graded as failed).\n\n", b.summary.refused);
  md += failures_and_effects_sections(b.summary);
  md += confusion_section(b.summary.confusion);
  md += params_and_time_sections(b);
  md += breakdown_sections(b);
  md += failed_cases_section(b);
  return md;
}

std::vector<fs::path> write_benchmark_outputs(const DiagnosisBenchmark& b, const fs::path& out,
                                              const std::string& command) {
  std::vector<fs::path> files;
  confusion_figure(b.summary.confusion, out / "confusion", b.options.cases);
  files.push_back(out / "confusion.png");
  files.push_back(out / "confusion.svg");
  core::write_atomically(out / "cases.csv", "benchmark cases", cases_csv(b));
  files.push_back(out / "cases.csv");
  core::write_atomically(out / "confusion.csv", "confusion matrix", confusion_csv(b.summary.confusion));
  files.push_back(out / "confusion.csv");
  core::write_atomically(out / "summary.md", "benchmark summary", benchmark_summary_markdown(b, command));
  files.push_back(out / "summary.md");
  return files;
}

std::string benchmark_command_line(const DiagnosisBenchmarkRequest& r) {
  const DiagnosisBenchmarkOptions d;
  const DiagnosisBenchmarkOptions& o = r.options;
  std::string c = fmt::format("odotune study diagnosis --cases {} --seed {}", o.cases, o.seed);
  if (o.first != d.first) c += fmt::format(" --first {}", o.first);
  if (o.draw.min_minutes != d.draw.min_minutes) c += fmt::format(" --min-minutes {:g}", o.draw.min_minutes);
  if (o.draw.max_minutes != d.draw.max_minutes) c += fmt::format(" --max-minutes {:g}", o.draw.max_minutes);
  if (o.draw.max_rate_hz != d.draw.max_rate_hz) c += fmt::format(" --max-rate {:g}", o.draw.max_rate_hz);
  if (o.draw.null_share != d.draw.null_share) c += fmt::format(" --null-share {:g}", o.draw.null_share);
  if (o.draw.two_share != d.draw.two_share) c += fmt::format(" --two-share {:g}", o.draw.two_share);
  if (o.draw.multi_share != d.draw.multi_share) c += fmt::format(" --multi-share {:g}", o.draw.multi_share);
  if (r.keep_tracks) c += " --keep-tracks";
  return c + " --out " + r.out;
}

StudyRun run_diagnosis_benchmark_to_folder(const DiagnosisBenchmarkRequest& request, const StudyHooks& hooks) {
  DiagnosisBenchmarkOptions o = request.options;
  const fs::path out(request.out);
  o.tracks_dir = request.keep_tracks ? (out / "tracks").string() : std::string();
  std::string why;
  if (!o.IsValid(&why)) throw core::Failure("study diagnosis: " + why);
  if (!results::gnuplot_available())
    throw core::Failure("study diagnosis: gnuplot not found on PATH (needed for the figure); install it "
                        "(apt-get install gnuplot)");
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw core::Failure(fmt::format("{}: --out exists and is not a folder", request.out));
  fs::create_directories(request.keep_tracks ? out / "tracks" : out, ec);
  if (ec)
    throw core::Failure(fmt::format("{}: cannot create the output folder: {}", request.out, ec.message()));

  BenchmarkProgress progress;
  if (hooks.progress) progress = [&hooks](long done, long total) { hooks.progress(done, total, ""); };
  DiagnosisBenchmark b;
  try {
    b = run_diagnosis_benchmark(o, progress, request.stop);
  } catch (const std::invalid_argument& e) {
    throw core::Failure(std::string("study diagnosis: ") + e.what());
  }
  const std::string command = benchmark_command_line(request);
  if (hooks.tables) {
    // The summary up to the confusion matrix (the rest is in the files).
    const std::string md = benchmark_summary_markdown(b, command);
    hooks.tables(md.substr(0, md.find("\n## Confusion matrix")) + "\n");
  }
  StudyRun run;
  run.files = write_benchmark_outputs(b, out, command);
  run.wall_s = b.wall_s;
  return run;
}

}  // namespace odotune::studies
