#include <odotune/studies/diagnosis_benchmark.h>

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/failure.h>
#include <odotune/core/stopwatch.h>
#include <odotune/core/why.h>
#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/diagnosis.h>
#include <odotune/diagnose/recordings.h>
#include <odotune/sim/effects.h>
#include <odotune/tracks/track_io.h>

namespace odotune::studies {

namespace {

using core::seconds_since;

using Clock = std::chrono::steady_clock;

using diagnose::Effect;
using diagnose::FindingKind;

template <class T>
bool contains(const std::vector<T>& v, const T& x) {
  return std::find(v.begin(), v.end(), x) != v.end();
}

// |values| at the nearest rank of quantile q (values non-empty).
double abs_quantile(std::vector<double> values, double q) {
  for (double& v : values) v = std::abs(v);
  std::sort(values.begin(), values.end());
  const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size())));
  return values[std::clamp<std::size_t>(k, 1, values.size()) - 1];
}

// Rows: the effects in table order, then "none"; columns: the finding kinds
// (the effects, then unexplained, in kind_index order), then "none".
constexpr std::size_t kNumKinds = diagnose::kNumEffects + 1;
std::size_t kind_index(const FindingKind& k) {
  const Effect* e = std::get_if<Effect>(&k);
  return e != nullptr ? static_cast<std::size_t>(*e) : static_cast<std::size_t>(diagnose::kNumEffects);
}
FindingKind kind_at(std::size_t i) {
  if (i < static_cast<std::size_t>(diagnose::kNumEffects)) return static_cast<Effect>(i);
  return diagnose::Unexplained{};
}
constexpr std::size_t kNone = kNumKinds;  // the "none" column; row kNumEffects is the "none" row

Confusion empty_confusion() {
  Confusion c;
  for (std::size_t i = 0; i < kNumKinds; ++i) {
    const FindingKind k = kind_at(i);
    if (std::holds_alternative<Effect>(k)) c.rows.emplace_back(diagnose::to_string(k));
    c.cols.emplace_back(diagnose::to_string(k));
  }
  c.rows.emplace_back("none");
  c.cols.emplace_back("none");
  c.counts.assign(c.rows.size(), std::vector<int>(c.cols.size(), 0));
  return c;
}

// Row: a true effect's index, or kNumEffects for none; column: kind_index or kNone.
void count(Confusion& c, std::size_t row, std::size_t col) { ++c.counts[row][col]; }

void add(Rate& rate, bool pass) {
  ++rate.cases;
  rate.passed += pass ? 1 : 0;
}

// Counts case r in its category of `rates`, and in its margin bucket.
void count_rates(CategoryRates& rates, const CaseResult& r) {
  const CaseGrade& g = r.grade;
  const auto bucket = static_cast<std::size_t>(margin_bucket(case_margin(r.truth)));
  switch (g.category) {
    case CaseCategory::null_case:
      add(rates.null_cases, g.pass);
      rates.null_with_finding += g.found.empty() ? 0 : 1;
      break;
    case CaseCategory::undetectable: add(rates.undetectable, g.pass); break;
    case CaseCategory::single:
      add(rates.single, g.pass);
      add(rates.single_by_margin[bucket], g.pass);
      break;
    case CaseCategory::two:
      add(rates.two, g.pass);
      add(rates.two_by_margin[bucket], g.pass);
      break;
  }
}

}  // namespace

double case_margin(const Detectability& truth) {
  double margin = std::numeric_limits<double>::infinity();
  for (const EffectTruth& t : truth.effects) {
    if (!t.detectable) continue;
    double m = t.floor_m > 0.0 ? t.gain_m / t.floor_m : 0.0;
    if (t.heading_floor_rad > 0.0) m = std::max(m, t.heading_gain_rad / t.heading_floor_rad);
    margin = std::min(margin, m);
  }
  return margin;
}

MarginBucket margin_bucket(double margin) {
  return margin < 1.5   ? MarginBucket::under_1_5
         : margin < 3.0 ? MarginBucket::from_1_5_to_3
                        : MarginBucket::from_3;
}

std::string_view to_string(MarginBucket b) {
  switch (b) {
    case MarginBucket::under_1_5: return "under 1.5 floors";
    case MarginBucket::from_1_5_to_3: return "1.5-3 floors";
    case MarginBucket::from_3: return "3 floors or more";
  }
  return "";
}

bool DiagnosisBenchmarkOptions::IsValid(std::string* why) const {
  if (cases < 1 || cases > 100000)
    return core::invalid(why, fmt::format("cases = {} must be in 1..100000", cases));
  if (first < 0 || first > 100000000)
    return core::invalid(why, fmt::format("first = {} must be in 0..100000000", first));
  if (threads < 0) return core::invalid(why, fmt::format("threads = {} must be >= 0", threads));
  std::string w;
  if (!draw.IsValid(&w)) return core::invalid(why, w);
  if (!materiality.IsValid(&w)) return core::invalid(why, "materiality: " + w);
  return true;
}

namespace {

// The case's effects, none judged detectable, with why (`note`).
Detectability not_judged(const std::vector<TrueEffect>& effects, const std::string& why, std::string* note) {
  Detectability d;
  for (const TrueEffect& e : effects) d.effects.push_back(EffectTruth{e});
  *note = "detectability not judged: " + why;
  return d;
}

void add_findings(CaseResult& r, const diagnose::Diagnosis& d) {
  for (const diagnose::Finding& f : d.findings)
    r.findings.push_back({.kind = f.kind,
                          .spec = f.spec(),
                          .heldout_before_m = f.heldout.before_pos_rmse_m,
                          .heldout_after_m = f.heldout.after_pos_rmse_m});
}

// A single-recording case (the header's file comment).
CaseResult run_single_case(const DiagnosisBenchmarkOptions& o, DiagnosisCase c) {
  CaseResult r;
  r.c = std::move(c);
  auto t0 = Clock::now();
  const CaseTrack ct = make_case_track(r.c);
  r.track_rows = static_cast<int>(ct.track.size());
  r.track_duration_s = ct.track.duration_s();
  if (!o.tracks_dir.empty())
    tracks::write_track(ct.track,
                        std::filesystem::path(o.tracks_dir) / fmt::format("case_{:04d}.csv", r.c.index));
  r.simulate_s = seconds_since(t0);

  t0 = Clock::now();
  std::optional<diagnose::DiagInput> in;
  std::string refusal;
  try {
    in = diagnose::build_diag_input(ct.track);
  } catch (const std::exception& e) {
    refusal = e.what();
  }
  const double input_s = seconds_since(t0);

  t0 = Clock::now();
  try {
    if (in) {
      r.truth = assess_detectability(*in, r.c.effects, o.materiality);
    } else {
      r.truth_note = "judged on the track's position fixes alone (the track was refused)";
      r.truth = assess_detectability(diagnose::build_diag_input(without_ground_truth(ct.track)), r.c.effects,
                                     o.materiality);
    }
  } catch (const std::exception& e) {
    r.truth = not_judged(r.c.effects, e.what(), &r.truth_note);
  }
  r.truth_s = seconds_since(t0);

  t0 = Clock::now();
  if (in) {
    try {
      const diagnose::Diagnosis d = diagnose::diagnose(*in);
      add_findings(r, d);
      r.grade = grade_case(r.truth.effects, d, r.c.scenario.robot.wheel_base_m,
                           TruePath{ct.path_x_m, ct.path_y_m, reference_gaps(in->ref_t_s),
                                    odometry_standstills(*in)});
    } catch (const std::exception& e) {
      refusal = e.what();
    }
  }
  if (!refusal.empty()) r.grade = grade_refusal(r.truth.effects, refusal);
  r.diagnose_s = input_s + seconds_since(t0);
  return r;
}

// The recordings' diagnosis inputs, fit recordings in `fit`, held-out ones in
// `held` (without ground truth when `fixes_only`). Throws what
// build_diag_input throws.
void recording_inputs(const DiagnosisCase& c, const std::vector<tracks::Track>& tracks, bool fixes_only,
                      std::vector<diagnose::DiagInput>& fit, std::vector<diagnose::DiagInput>& held) {
  fit.clear();
  held.clear();
  for (std::size_t k = 0; k < tracks.size(); ++k)
    (c.recordings[k].heldout ? held : fit)
        .push_back(diagnose::build_diag_input(fixes_only ? without_ground_truth(tracks[k]) : tracks[k]));
}

// A multi-recording case: diagnosed as `odotune diagnose FIT... --heldout
// HELD...` does (diagnose::diagnose_recordings at default options), judged
// by assess_recordings_detectability, graded as a single-recording case.
CaseResult run_multi_case(const DiagnosisBenchmarkOptions& o, DiagnosisCase c) {
  CaseResult r;
  r.c = std::move(c);
  auto t0 = Clock::now();
  std::vector<tracks::Track> tracks;
  for (std::size_t k = 0; k < r.c.recordings.size(); ++k) {
    CaseTrack ct = make_recording_track(r.c, k);
    r.track_rows += static_cast<int>(ct.track.size());
    r.track_duration_s += ct.track.duration_s();
    if (!o.tracks_dir.empty())
      tracks::write_track(ct.track, std::filesystem::path(o.tracks_dir) /
                                        fmt::format("case_{:04d}_r{}.csv", r.c.index, k + 1));
    tracks.push_back(std::move(ct.track));
  }
  r.simulate_s = seconds_since(t0);

  t0 = Clock::now();
  std::vector<diagnose::DiagInput> fit, held;
  std::string refusal;
  try {
    recording_inputs(r.c, tracks, false, fit, held);
  } catch (const std::exception& e) {
    refusal = e.what();
  }
  const double input_s = seconds_since(t0);

  t0 = Clock::now();
  try {
    if (refusal.empty()) {
      r.truth = assess_recordings_detectability(fit, held, r.c.effects, o.materiality);
    } else {
      r.truth_note = "judged on the recordings' position fixes alone (a recording was refused)";
      std::vector<diagnose::DiagInput> fit_fixes, held_fixes;
      recording_inputs(r.c, tracks, true, fit_fixes, held_fixes);
      r.truth = assess_recordings_detectability(fit_fixes, held_fixes, r.c.effects, o.materiality);
    }
  } catch (const std::exception& e) {
    r.truth = not_judged(r.c.effects, e.what(), &r.truth_note);
  }
  r.truth_s = seconds_since(t0);

  t0 = Clock::now();
  if (refusal.empty()) {
    try {
      const diagnose::PooledDiagnosis p = diagnose::diagnose_recordings(fit, held);
      add_findings(r, p.pooled);
      r.grade = grade_case(r.truth.effects, p.pooled, r.c.scenario.robot.wheel_base_m, TruePath{});
    } catch (const std::exception& e) {
      refusal = e.what();
    }
  }
  if (!refusal.empty()) r.grade = grade_refusal(r.truth.effects, refusal);
  r.diagnose_s = input_s + seconds_since(t0);
  return r;
}

}  // namespace

CaseResult run_benchmark_case(const DiagnosisBenchmarkOptions& o, int index) {
  DiagnosisCase c = draw_case(case_seed(o.seed, index), index, o.draw);
  return c.multi() ? run_multi_case(o, std::move(c)) : run_single_case(o, std::move(c));
}

DiagnosisBenchmark run_diagnosis_benchmark(const DiagnosisBenchmarkOptions& o,
                                           const BenchmarkProgress& progress, const std::atomic<bool>* stop) {
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument("study diagnosis: " + why);
  const auto t0 = Clock::now();
  DiagnosisBenchmark b;
  b.options = o;
  b.threads_used = o.threads > 0 ? o.threads : omp_get_max_threads();
  b.cases.resize(static_cast<std::size_t>(o.cases));
  std::string failure;
  bool invalid = false, stopped = false;
  long done = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(b.threads_used)
  for (int k = 0; k < o.cases; ++k) {
    bool skip = false;
#pragma omp critical(odotune_diag_bench)
    {
      stopped = stopped || (stop != nullptr && stop->load());
      skip = !failure.empty() || stopped;
    }
    if (skip) continue;
    try {
      b.cases[static_cast<std::size_t>(k)] = run_benchmark_case(o, o.first + k);
    } catch (const std::invalid_argument& e) {
#pragma omp critical(odotune_diag_bench)
      if (failure.empty()) {
        failure = e.what();
        invalid = true;
      }
    } catch (const std::exception& e) {
#pragma omp critical(odotune_diag_bench)
      if (failure.empty()) failure = e.what();
    }
#pragma omp critical(odotune_diag_bench)
    {
      ++done;
      if (progress) progress(done, o.cases);
    }
  }
  if (!failure.empty()) {
    if (invalid) throw std::invalid_argument(failure);
    throw std::runtime_error(failure);
  }
  if (stopped) throw core::Failure("study diagnosis: interrupted", 130);
  b.summary = summarise(b.cases);
  b.wall_s = seconds_since(t0);
  return b;
}

BenchmarkSummary summarise(const std::vector<CaseResult>& cases) {
  BenchmarkSummary s;
  s.confusion = empty_confusion();
  std::map<std::size_t, EffectScore> scores;  // by kind_index
  std::map<std::string, std::vector<double>> param_errors;
  std::map<std::string, int> param_within;
  std::vector<double> times;
  for (const CaseResult& r : cases) {
    const CaseGrade& g = r.grade;
    count_rates(r.c.multi() ? s.multi_recording : s.single_recording, r);
    ++s.all.cases;
    s.all.passed += g.pass ? 1 : 0;
    s.refused += g.refused ? 1 : 0;
    if (!g.pass) {
      if (g.refused) ++s.failures["refused"];
      if (!g.missed.empty() && !g.refused) ++s.failures["missed an effect"];
      if (!g.extra.empty()) ++s.failures["named a wrong effect"];
      if (!g.refused && !g.params_ok) ++s.failures["parameter out of tolerance"];
      if (!g.refused && !g.heldout_ok) ++s.failures["held-out not improved"];
    }

    // Confusion matrix.
    const std::size_t none_row = diagnose::kNumEffects;
    for (Effect e : g.expected)
      if (contains(g.found, FindingKind{e})) count(s.confusion, kind_index(e), kind_index(e));
    for (Effect e : g.missed) {
      if (g.extra.empty()) count(s.confusion, kind_index(e), kNone);
      for (const FindingKind& x : g.extra) count(s.confusion, kind_index(e), kind_index(x));
    }
    if (g.missed.empty())
      for (const FindingKind& x : g.extra) count(s.confusion, none_row, kind_index(x));
    if (g.expected.empty() && g.extra.empty()) count(s.confusion, none_row, kNone);

    // Per-effect scores.
    for (Effect e : g.expected) {
      EffectScore& sc = scores[kind_index(e)];
      ++sc.expected;
      sc.named_expected += contains(g.found, FindingKind{e}) ? 1 : 0;
      sc.right += g.pass ? 1 : 0;
    }
    for (const FindingKind& f : g.found) {
      const Effect* e = std::get_if<Effect>(&f);
      if (e == nullptr || !contains(g.tolerated, *e)) ++scores[kind_index(f)].named;
    }

    for (const ParamCheck& p : g.params) {
      if (!p.graded) continue;
      const std::string name = fmt::format("{}.{}", diagnose::effect_name(p.effect), p.param);
      if (std::isfinite(p.normalised)) param_errors[name].push_back(p.normalised);
      param_within[name] += p.ok ? 1 : 0;
    }
    times.push_back(r.total_s());
    s.diagnose_mean_s += r.diagnose_s;
  }
  for (auto& [index, score] : scores) {  // kind_index order: table order, then unexplained
    score.effect = kind_at(index);
    s.effects.push_back(score);
  }
  for (const auto& [name, errors] : param_errors) {
    ParamStats p;
    p.name = name;
    p.n = static_cast<int>(errors.size());
    p.within = param_within[name];
    if (!errors.empty()) {
      p.median_abs = abs_quantile(errors, 0.5);
      p.p90_abs = abs_quantile(errors, 0.9);
      p.max_abs = abs_quantile(errors, 1.0);
    }
    s.params.push_back(p);
  }
  if (!times.empty()) {
    double sum = 0.0;
    for (double t : times) sum += t;
    s.time_mean_s = sum / static_cast<double>(times.size());
    s.time_median_s = abs_quantile(times, 0.5);
    s.time_max_s = abs_quantile(times, 1.0);
    s.diagnose_mean_s /= static_cast<double>(times.size());
  }
  return s;
}

}  // namespace odotune::studies
