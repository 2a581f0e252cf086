// The random benchmark of the sim-to-real diagnosis (`odotune study
// diagnosis`; method in docs/diagnosis/benchmark.md): cases
// first .. first + cases - 1 of a seed are drawn (diagnosis_cases.h),
// simulated, judged detectable from their truth (diagnosis_truth.h),
// diagnosed (diagnose::diagnose at default options on
// diagnose::build_diag_input of the track, as `odotune diagnose TRACK` does)
// and graded (diagnosis_grading.h). A multi-recording case (2-4 recordings of
// one robot, diagnosis_cases.h) is diagnosed as `odotune diagnose FIT...
// --heldout HELD...` does (diagnose::diagnose_recordings at default options
// on each recording's build_diag_input), judged on its held-out recordings
// (assess_recordings_detectability) and graded by the same rules, with the
// held-out recordings' numbers (odotune/diagnose/recordings.h). Then summarised: pass rates per category
// against the aims (docs/diagnosis/benchmark.md), a confusion matrix of true × named effects,
// per-effect recall and precision, parameter errors and time per case.
//
// Seeds. Case i of seed S uses case_seed(S, i) for everything, so a case
// re-runs alone (`--first i --cases 1`) and every number but the timings is
// bit-identical for any thread count. Development runs use seeds 1001-1003;
// the committed docs run (docs/diagnosis/) uses a seed kept apart from
// development (kDocsSeed), so that its numbers measure generalisation.
//
// Refusals. A track the diagnosis refuses (build_diag_input or diagnose
// throws std::invalid_argument: e.g. today's "known start + fixes") is a
// failed case carrying the message; when build_diag_input refused it, its
// detectability is judged on the same track without its ground truth (the
// fixes alone), and so is the category. Likewise for a multi-recording case
// when any of its recordings is refused. A case that cannot be simulated is a bug and stops the run.
//
// Cases run in parallel over OpenMP threads (one case per task, dynamic
// schedule); each task is single-threaded. Progress through a callback (from
// one thread at a time); the stop flag ends the run before the next case
// starts (core::Failure "interrupted", exit code 130). No output here:
// diagnosis_benchmark_outputs.h writes the files.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <odotune/diagnose/finding_kind.h>
#include <odotune/diagnose/materiality.h>
#include <odotune/studies/diagnosis_cases.h>
#include <odotune/studies/diagnosis_grading.h>
#include <odotune/studies/diagnosis_truth.h>

namespace odotune::studies {

// The docs run's seed (never used while developing; development: 1001-1004).
// 20261125, 20261126 and 20261127 were earlier docs seeds, retired once their
// failure lists had been read (docs/diagnosis/benchmark.md, "Seeds").
inline constexpr std::uint64_t kDocsSeed = 20261128;

struct DiagnosisBenchmarkOptions {
  int cases = 300;                           // 1..100000
  int first = 0;                             // index of the first case, >= 0
  std::uint64_t seed = 1;                    // case i: case_seed(seed, i)
  int threads = 0;                           // OpenMP threads over cases; 0 = OpenMP's default
  CaseDrawOptions draw;                      // what a case draws
  diagnose::MaterialityOptions materiality;  // the floor of detectability
  // When set: each case's track written there as case_IIII.csv, each
  // recording of a multi-recording case as case_IIII_rK.csv (K from 1).
  std::string tracks_dir;
  bool IsValid(std::string* why) const;
};

struct CaseFinding {
  diagnose::FindingKind kind;
  std::string spec;  // odotune/sim/effects.h form ("" for unexplained)
  double heldout_before_m = std::numeric_limits<double>::quiet_NaN();
  double heldout_after_m = std::numeric_limits<double>::quiet_NaN();
};

struct CaseResult {
  DiagnosisCase c;
  int track_rows = 0;
  double track_duration_s = 0.0;
  Detectability truth;
  std::string truth_note;  // "" or how detectability was judged on a refused track
  std::vector<CaseFinding> findings;
  CaseGrade grade;
  double simulate_s = 0.0, truth_s = 0.0, diagnose_s = 0.0;  // timing [s]
  double total_s() const { return simulate_s + truth_s + diagnose_s; }
};

// Pass counts of one category.
struct Rate {
  int cases = 0, passed = 0;
  double share() const { return cases > 0 ? static_cast<double>(passed) / cases : std::nan(""); }
};

struct EffectScore {
  diagnose::FindingKind effect;
  int expected = 0;        // cases where it is detectable
  int named_expected = 0;  // ... and named (recall numerator)
  int right = 0;           // ... and the case passed
  int named = 0;           // cases where it is named and not tolerated (precision denominator)
  double recall() const { return expected > 0 ? static_cast<double>(named_expected) / expected : std::nan(""); }
  double precision() const { return named > 0 ? static_cast<double>(named_expected) / named : std::nan(""); }
};

struct ParamStats {
  std::string name;  // "effect.param" (slip_zone.box: the path rule's error)
  int n = 0, within = 0;
  double median_abs = std::nan(""), p90_abs = std::nan(""), max_abs = std::nan("");  // |normalised|
};

// Rows: the 12 effects then "none" (no detectable effect); columns: the 12
// effects, `unexplained`, then "none" (nothing wrong named). Per case: each
// expected effect that is named counts (e, e); each missed one (e, x) for
// every extra finding x, or (e, none) when there is none; extra findings
// with nothing missed count (none, x); a case with nothing expected and
// nothing wrong named counts (none, none). A refused case counts its
// expected effects as missed with nothing named.
struct Confusion {
  std::vector<std::string> rows, cols;
  std::vector<std::vector<int>> counts;  // [row][col]
};

// A case's margin: the smallest, over its detectable effects, of the true
// gain over its floor (EffectTruth: gain_m / floor_m, or the heading ratio
// when that is larger); +infinity without a detectable effect.
double case_margin(const Detectability& truth);

// The margin buckets the aims are stated in (docs/diagnosis/benchmark.md,
// "Aims"): under 1.5 floors (no aim), 1.5 to 3 floors, 3 floors or more.
enum class MarginBucket { under_1_5, from_1_5_to_3, from_3 };
inline constexpr std::size_t kMarginBuckets = 3;
MarginBucket margin_bucket(double margin);   // < 1.5, [1.5, 3), >= 3
std::string_view to_string(MarginBucket b);  // "under 1.5 floors", "1.5-3 floors", "3 floors or more"

// The aims by margin (docs/diagnosis/benchmark.md, "Aims"): the least share
// of single and two-effect cases right per margin bucket (indexed by
// MarginBucket; NaN: reported, no aim), and the largest share of null cases
// with any finding.
inline constexpr std::array<double, kMarginBuckets> kSingleEffectAims = {
    std::numeric_limits<double>::quiet_NaN(), 0.75, 0.97};
inline constexpr std::array<double, kMarginBuckets> kTwoEffectAims = {std::numeric_limits<double>::quiet_NaN(),
                                                                      0.60, 0.90};
inline constexpr double kNullFindingAim = 0.02;

// Pass counts per category, and of single and two-effect cases per margin
// bucket (indexed by MarginBucket).
struct CategoryRates {
  Rate null_cases, undetectable, single, two;
  int null_with_finding = 0;  // null cases with any finding (refusals are not findings)
  std::array<Rate, kMarginBuckets> single_by_margin{}, two_by_margin{};
  // Share of null cases with any finding (NaN without null cases).
  double null_finding_share() const {
    return null_cases.cases > 0 ? static_cast<double>(null_with_finding) / null_cases.cases : std::nan("");
  }
};

struct BenchmarkSummary {
  CategoryRates single_recording;  // cases of one recording
  CategoryRates multi_recording;   // multi-recording cases (diagnosis_cases.h)
  Rate all;
  int refused = 0;
  std::map<std::string, int>
      failures;  // failure kind -> cases (missed, wrong effect, parameter, held-out, refused)
  Confusion confusion;
  std::vector<EffectScore> effects;  // table order, effects that occur
  std::vector<ParamStats> params;
  double time_mean_s = 0.0, time_median_s = 0.0, time_max_s = 0.0, diagnose_mean_s = 0.0;
};

struct DiagnosisBenchmark {
  DiagnosisBenchmarkOptions options;
  int threads_used = 0;
  std::vector<CaseResult> cases;  // index order
  BenchmarkSummary summary;
  double wall_s = 0.0;
};

using BenchmarkProgress = std::function<void(long done, long total)>;

// One case end to end (the file comment). Throws std::invalid_argument when
// the case cannot be simulated; writes its track when tracks_dir is set
// (std::runtime_error when that fails).
CaseResult run_benchmark_case(const DiagnosisBenchmarkOptions& options, int index);

// The whole run. Throws std::invalid_argument for invalid options, and what
// run_benchmark_case throws (the first such error, after the running cases
// finish); core::Failure (code 130) when stopped.
DiagnosisBenchmark run_diagnosis_benchmark(const DiagnosisBenchmarkOptions& options,
                                           const BenchmarkProgress& progress = {},
                                           const std::atomic<bool>* stop = nullptr);

// The summary of graded cases (the fields' comments).
BenchmarkSummary summarise(const std::vector<CaseResult>& cases);

}  // namespace odotune::studies
