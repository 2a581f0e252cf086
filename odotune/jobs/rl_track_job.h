// robot_localization's EKF on the project's tracks (odotune/objectives/rl_track.h):
// `odotune eval --rl-params P --track T…` replays each track and scores the
// filter against its ground truth (the run with every fix fused, simulated
// fix outages) and against its fixes (the tune's protocols);
// `odotune tune --rl-params P --track T…` tunes one file on all the tracks
// together, without their ground truth (odotune/jobs/rl_job.h's search), and writes
// the user's file with the tuned values.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <odotune/jobs/rl_job.h>
#include <odotune/objectives/rl_track.h>

namespace odotune::jobs {

struct RlTrackSource {
  std::filesystem::path params_file;
  std::string node_name;
  std::optional<filters::rl::RlFilterType> filter;  // as RlSource::filter
  std::vector<std::filesystem::path> tracks;
  objectives::RlTrackOptions options;
  // A calibration file (calibrate --config-out) applied to every track's
  // odometry (RlTrackOptions::wheels or twist); empty: none.
  std::filesystem::path calibration;
};

struct RlTracksLoaded {
  rlnode::RlParams params;
  std::vector<objectives::RlTrack> tracks;
};
// Reads the file and every track; throws Failure with one line.
RlTracksLoaded load_rl_tracks(const RlTrackSource& src);

// One track under one setting.
struct RlTrackRow {
  std::filesystem::path track;
  tracks::OdometryInput odometry = tracks::OdometryInput::wheels;
  std::string start_note;
  double initial_heading_error_rad = 0.0;  // NaN without gt_theta
  double duration_s = 0.0;
  objectives::RlTrackScores scores;
};
std::vector<RlTrackRow> score_rl_tracks(const RlTracksLoaded& loaded, const rlnode::ReplaySettings& s,
                                        const objectives::RlTuneOptions& protocols,
                                        bool keep_trajectory = false);

struct RlTrackEvalRequest {
  RlTrackSource src;
  // Another robot_localization file whose process_noise_covariance replaces
  // this file's; empty: none.
  std::filesystem::path noise_from;
  objectives::RlTuneOptions protocols;             // the outage windows and held-out folds scored
  std::filesystem::path trajectory_out, json_out;  // trajectory: one track only
};
struct RlTrackEvalOutcome {
  std::filesystem::path params_file;
  filters::rl::RlFilterType filter = filters::rl::RlFilterType::ekf;  // the file's (or --filter's)
  std::vector<RlTrackRow> rows;
  // Over all tracks together.
  objectives::TruthScore run, outages;
  objectives::FixScore heldout_fixes, outage_fixes;
};
// Throws Failure with one line; nothing is written then.
RlTrackEvalOutcome run_rl_track_eval(const RlTrackEvalRequest& request);

// The tune of RlTuneRequest (its span options refused: a track is tuned
// whole) on `tracks`; besides the outcome's scores on the fixes, each track's
// scores against its ground truth for the file's and the tuned values (not
// seen by the tune) in `before` and `after`.
struct RlTrackTuneOutcome {
  RlTuneOutcome tune;
  std::vector<RlTrackRow> before, after;
};
RlTrackTuneOutcome run_rl_track_tune(const RlTuneRequest& request, const RlTrackSource& src);

}  // namespace odotune::jobs
