// robot_localization's EKF on a robot's own bag and parameter file:
// `odotune eval --rl-params P --bag B` replays and scores it,
// `odotune tune --rl-params P --bag B` tunes its process noise (and advises
// its inputs' covariances) and writes the user's file back with the tuned
// values (rlnode/ replays the node, odotune/objectives/rl_objective.h scores it).
//
// Scores without ground truth, in the odom frame, by the GPS fixes as
// navsat_transform_node turns them into odometry:
//   held-out fixes  5 folds of 1 s blocks, the prediction at each held-out fix;
//   outage          GPS fused until `from`, none after; the error at every later fix;
//   every 5th       GPS fused until `from`; after it every 5th fix held out.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <odotune/formats/experiment_yaml.h>
#include <odotune/jobs/report_job.h>
#include <odotune/jobs/rl_search.h>
#include <odotune/jobs/tune_job.h>
#include <odotune/objectives/rl_bag_scores.h>
#include <odotune/objectives/rl_objective.h>
#include <odotune/objectives/rl_protocols.h>
#include <odotune/results/run_record.h>
#include <odotune/results/store.h>
#include <odotune/rlnode/gps_alignment.h>
#include <odotune/rlnode/params.h>
#include <odotune/rlnode/recording.h>
#include <odotune/rlnode/replay.h>
#include <odotune/tuner/summary.h>

namespace odotune::jobs {

struct RlSource {
  std::filesystem::path params_file, bag;
  std::filesystem::path navsat_params;  // --navsat-params: navsat_transform_node's own file (empty: none)
  std::string node_name;                // the filter's section of the file when it has several
  std::optional<filters::rl::RlFilterType>
      filter;                      // --filter: for a file that does not say (odotune/rlnode/params.h)
  std::vector<std::string> tf;     // "FRAME=x,y,z,roll,pitch,yaw": FRAME's pose in base_link [m, rad]
  std::string gps_topic;           // NavSatFix topic behind navsat's output (empty: the bag's one)
  std::vector<std::string> remap;  // "FROM=TO": the node's subscription to FROM reads the bag's TO
  double gps_heading_fit_s = 0;  // > 0: fit navsat's rotation on the first seconds instead of the IMU's heading
  double from_s = 0;             // > 0: the bag as if recorded from this many seconds after its first message
};

struct RlLoaded {
  rlnode::Recording rec;
  std::optional<rlnode::GpsAlignment> alignment;
};
// Reads the parameter file and the bag; throws Failure with one line.
RlLoaded load_rl(const RlSource& src);
// An experiment's robot_localization section applied to one of its bags.
RlSource rl_source_of(const formats::ExperimentRl& x, const std::filesystem::path& bag,
                      std::optional<filters::rl::RlFilterType> filter = std::nullopt);

// The filter's trajectory in TUM format (t x y z qx qy qz qw) on the
// recording's clock, `comment` as its first line; throws Failure.
void write_rl_trajectory(const std::filesystem::path& path, const std::vector<rlnode::TrajectoryPoint>& points,
                         const std::string& comment);

// process_noise_covariance of another robot_localization file's `node_name`
// section (it need not configure inputs): eval --noise-from. Throws Failure.
rlnode::Matrix15 rl_noise_from(const std::filesystem::path& file, const std::string& node_name);

// A user's seconds (from the recording's first message) as a stamp, and back.
std::int64_t rl_time_ns(const rlnode::Recording& rec, double seconds);
double rl_seconds(const rlnode::Recording& rec, std::int64_t time_ns);

// "FRAME=x,y,z,roll,pitch,yaw" → (FRAME, pose); throws Failure naming the flag.
std::pair<std::string, rlnode::Pose3> parse_tf(const std::string& text);
// The parameter file of `src` alone (its bag not read): its keys'
// RlParams::keys and notes, for `eval --keys`; throws Failure with one line.
rlnode::RlParams read_rl_file(const RlSource& src);
// An error [m] for the user: "1.23 m" with `decimals` places, or "diverged"
// when it is not finite (a diverged filter's NaN).
std::string rmse_text(int decimals, double v_m);
// "FROM=TO" (--remap); throws Failure with one line otherwise.
std::pair<std::string, std::string> parse_remap(const std::string& text);

// The protocols' scores and a judged span (odotune/objectives/rl_bag_scores.h):
// after a tune's span both protocols start where it ends; before it (tune
// --from), the outage starts once the heading fit's fixes are fused, and every
// 5th fix of the span is held out.
using RlProtocolScores = objectives::RlProtocolScores;
using RlJudgedSpan = objectives::RlJudgedSpan;

struct RlEvalRequest {
  RlSource src;
  std::optional<double> until_s, from_s;  // seconds from the recording's first message
  // Another robot_localization file whose process_noise_covariance replaces
  // this file's (e.g. a noise exported from another model); empty: none.
  std::filesystem::path noise_from;
  std::filesystem::path trajectory_out, json_out;
  std::filesystem::path fixes_out;  // the GPS fixes in the odom frame (t x y), as navsat placed them
  // Simulated outages of these lengths [s], one of each starting every
  // outage_every_s from from_s (or 30 s after the first fix) to until_s.
  std::vector<double> outages_s;
  double outage_every_s = 10.0;
};

struct RlEvalOutcome {
  std::filesystem::path bag, params_file;
  filters::rl::RlFilterType filter = filters::rl::RlFilterType::ekf;  // the file's (or --filter's)
  filters::rl::State final_state;
  double duration_s = 0.0;
  long processed = 0, rejected = 0;
  std::optional<objectives::FixScore> heldout;  // 5 folds of 1 s blocks over the span
  std::optional<RlProtocolScores> protocols;    // with from_s
  std::optional<objectives::FixScore> outages;  // with outages_s
  std::size_t outage_windows = 0;
  std::optional<rlnode::GpsAlignment> alignment;
  std::vector<std::string> notes;
};
RlEvalOutcome run_rl_eval(const RlEvalRequest& request);

struct RlTuneRequest : SolverSettings {
  RlSource src;
  // Tune on the recording before until_s and judge after it; or (from_s)
  // tune on the recording after from_s, the bag cut there, and judge before it.
  std::optional<double> until_s, from_s;  // [s] from the recording's first message
  std::optional<double> end_s;            // ignore the recording after this [s]
  // Judging before from_s: the GPS fused for this long before the outage.
  double lead_in_s = 60.0;
  objectives::RlTuneOptions options;
  objectives::RlSearchOptions search;
  int starts = 1;  // refinements from seeds seed, seed + 1, …; the lowest tuning fitness is written
  std::filesystem::path config_out, json_out;
  bool ros1_out = false;                  // write the ROS 1 form (default ROS 2)
  std::filesystem::path config_out_ros1;  // also the ROS 1 form, here
  std::filesystem::path starts_out;       // a folder: each start's file as ekf-seed<K>.yaml
  std::string command_line;               // for the file's provenance comment

  bool IsValid(std::string* why) const;
};

// One start of a tune: its seed's refinement and profile.
struct RlStartOutcome {
  std::uint64_t seed = 0;
  std::vector<double> factors;  // per parameter: the tuned multiplier
  rlnode::ReplaySettings tuned;
  double fitness = 0.0;                    // tuning (data) fitness
  objectives::FixScore heldout, outage;    // on the tuning span
  std::optional<RlProtocolScores> judged;  // on the judged span: never seen by the tune
  std::vector<RlParamProfile> profiles;    // per parameter (empty without a profile)
  long evaluations = 0;
  double seconds = 0.0;
};

struct RlTuneOutcome {
  std::filesystem::path bag, params_file;
  filters::rl::RlFilterType filter = filters::rl::RlFilterType::ekf;  // the file's (or --filter's)
  std::vector<std::filesystem::path> tracks;  // tuned on tracks (odotune/jobs/rl_track_job.h), not a bag
  double duration_s = 0.0;
  double span_from_s = 0.0, span_until_s = 0.0;  // the tuning span [s]
  std::optional<RlJudgedSpan> judged;            // the judged span, when there is one
  double judged_from_s = 0.0, judged_until_s = 0.0;
  std::vector<std::string> param_names;
  std::vector<double> factors;  // the written start's
  rlnode::ReplaySettings baseline, tuned;
  double baseline_fitness = 0.0, tuned_fitness = 0.0;
  objectives::FixScore baseline_heldout, tuned_heldout, baseline_outage, tuned_outage;  // on the tuning span
  std::optional<RlProtocolScores> baseline_judged, tuned_judged;  // never seen by the tune
  std::size_t outage_windows = 0;
  RlGridResult grid;
  std::vector<RlStartOutcome> starts;
  std::size_t written = 0;  // the start of lowest tuning fitness
  tuner::Summary summary;   // the written start's run: all its stages' evaluations and time
  long diverged = 0;        // evaluations whose replay diverged
  std::optional<rlnode::GpsAlignment> alignment;
  std::vector<std::string> notes;
};
// The comment at the top of start k's written file: where it came from, what
// it scored, the starts' spread and what the recording did not determine.
std::string rl_tune_header(const RlTuneRequest& r, const RlTuneOutcome& o, std::size_t k);
// tune --json: the request, every start, the written one's factors with their ranges.
void write_rl_tune_json(const std::filesystem::path& path, const RlTuneRequest& r, const RlTuneOutcome& o);
// Validates the request, reads the file and the bag, tunes (tune_rl) and
// writes the requested files. Throws Failure with one line.
RlTuneOutcome run_rl_tune(const RlTuneRequest& request);
// The user's file `params` with `tuned`'s process noise (and, with
// `alignment`, navsat's yaw_offset) written to `path`, ROS 2 or ROS 1, with
// `header` followed by navsat's fitted rotation (fitted on the first fit_s)
// and the advised input covariances as comments. Throws Failure; nothing is
// written then.
void write_tuned_params(const std::filesystem::path& path, const rlnode::RlParams& params,
                        const rlnode::ReplaySettings& tuned,
                        const std::optional<rlnode::GpsAlignment>& alignment, double fit_s, bool ros2,
                        std::string header);
// A stored rl-ekf run (a grid's results store; model rl-ekf) written as the
// robot's parameter file: the experiment's file with the run's factors
// applied, navsat's yaw_offset when the experiment fits the GPS heading, the
// held-out scores and `provenance` in comments. Reads the run's bag again.
// Throws Failure with one line; nothing is written then.
void write_rl_run(const formats::Experiment& e, const results::RunRecord& run, const std::filesystem::path& out,
                  bool ros2, const std::string& provenance);
// `odotune report` for a store of rl-ekf runs (odotune/jobs/report_job.h calls it):
// the held-out GPS-outage errors per bag and fitness, improvement per
// fitness, the seeds' spread, each parameter's determined range per seed,
// the best run's outage trajectory per bag and fitness (the run of lowest
// tuning fitness, replayed from the bag) and convergence curves.
ReportOutcome write_rl_report(const ReportRequest& req, const results::ExperimentInfo& info,
                              const std::vector<results::RunRecord>& runs);
// The grid, the starts and the written one on `objective`: an outcome with
// the search's fields (param_names, outage_windows, the baseline's and each
// start's scores on the tuning span, grid, starts, written, factors, tuned,
// tuned_fitness, tuned_heldout, tuned_outage, summary, diverged); the others,
// the judged scores among them, are left for the caller. Throws Failure when
// stopped before the first start.
RlTuneOutcome search_rl(const objectives::RlObjective& objective, const RlTuneRequest& request);
// The search and its scores on an already loaded recording (no file read or
// written; the request's output paths are not used); with from_s, `tuned_on`
// is the recording cut there (load_rl with RlSource::from_s), `loaded` the
// whole one it is judged on. Throws Failure.
RlTuneOutcome tune_rl(const RlLoaded& loaded, const RlTuneRequest& request, const RlLoaded* tuned_on = nullptr);

}  // namespace odotune::jobs
