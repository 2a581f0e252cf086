#include <odotune/jobs/rl_track_job.h>

#include <cmath>
#include <numbers>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <odotune/core/atomic_file.h>
#include <odotune/core/failure.h>
#include <odotune/core/output_paths.h>
#include <odotune/formats/calibration_yaml.h>
#include <odotune/tracks/track_io.h>

namespace odotune::jobs {

RlTracksLoaded load_rl_tracks(const RlTrackSource& src) {
  if (src.tracks.empty()) throw core::Failure("--rl-params with tracks: expected at least one --track");
  std::string why;
  if (!src.options.IsValid(&why)) throw core::Failure(why);
  RlTracksLoaded out;
  objectives::RlTrackOptions options = src.options;
  if (!src.calibration.empty()) {
    const formats::CalibrationFile c = formats::read_calibration_file(src.calibration);
    if (c.odometry == tracks::OdometryInput::wheels) {
      options.wheels = c.params;
    } else {
      options.twist = c.twist;
    }
  }
  try {
    out.params = rlnode::read_rl_params(src.params_file, src.node_name, src.filter);
    for (const std::filesystem::path& path : src.tracks)
      out.tracks.push_back(objectives::load_rl_track(tracks::read_track(path), path, out.params, options));
  } catch (const core::Failure&) {
    throw;
  } catch (const std::exception& e) {
    throw core::Failure(e.what());
  }
  return out;
}

std::vector<RlTrackRow> score_rl_tracks(const RlTracksLoaded& loaded, const rlnode::ReplaySettings& s,
                                        const objectives::RlTuneOptions& protocols, bool keep_trajectory) {
  std::vector<RlTrackRow> rows;
  for (const objectives::RlTrack& t : loaded.tracks) {
    RlTrackRow r;
    r.track = t.file;
    r.odometry = t.odometry;
    r.start_note = t.start_note;
    r.initial_heading_error_rad = t.initial_heading_error_rad;
    r.duration_s = static_cast<double>(t.rec.end_ns - t.rec.start_ns) * 1e-9;
    try {
      r.scores = objectives::score_rl_track(t, s, protocols, keep_trajectory);
    } catch (const std::exception& e) {
      throw core::Failure(e.what());
    }
    rows.push_back(std::move(r));
  }
  return rows;
}

namespace {

nlohmann::json track_json_of(const objectives::TruthScore& s) {
  return {{"rmse_m", s.rmse_m},
          {"mae_m", s.mae_m},
          {"max_m", s.max_m},
          {"samples", s.samples},
          {"finite", s.finite}};
}

nlohmann::json track_json_of(const objectives::FixScore& s) {
  return {{"rmse_m", s.rmse_m}, {"fixes", s.fixes}, {"finite", s.finite}};
}

nlohmann::json track_json_of(const RlTrackRow& r) {
  return {
      {"track", r.track.string()},
      {"odometry", tracks::to_string(r.odometry)},
      {"start", r.start_note},
      {"initial_heading_error_rad", std::isfinite(r.initial_heading_error_rad)
                                        ? nlohmann::json(r.initial_heading_error_rad)
                                        : nlohmann::json()},
      {"duration_s", r.duration_s},
      {"truth", {{"run", track_json_of(r.scores.run)}, {"outages", track_json_of(r.scores.outages)}}},
      {"fixes",
       {{"heldout", track_json_of(r.scores.heldout_fixes)}, {"outages", track_json_of(r.scores.outage_fixes)}}},
      {"outage_windows", r.scores.windows},
      {"processed", r.scores.processed},
      {"rejected", r.scores.rejected}};
}

// The rows' scores over all tracks together.
void pool_rows(const std::vector<RlTrackRow>& rows, RlTrackEvalOutcome& o) {
  std::vector<objectives::TruthScore> run, out;
  std::vector<objectives::FixScore> held, fix_out;
  for (const RlTrackRow& r : rows) {
    run.push_back(r.scores.run);
    out.push_back(r.scores.outages);
    held.push_back(r.scores.heldout_fixes);
    fix_out.push_back(r.scores.outage_fixes);
  }
  o.run = objectives::pooled(std::span<const objectives::TruthScore>(run));
  o.outages = objectives::pooled(std::span<const objectives::TruthScore>(out));
  o.heldout_fixes = objectives::pooled(std::span<const objectives::FixScore>(held));
  o.outage_fixes = objectives::pooled(std::span<const objectives::FixScore>(fix_out));
}

}  // namespace

RlTrackEvalOutcome run_rl_track_eval(const RlTrackEvalRequest& request) {
  std::string why;
  if (!request.protocols.IsValid(&why)) throw core::Failure("eval: " + why);
  if (!request.trajectory_out.empty()) {
    if (request.src.tracks.size() != 1) throw core::Failure("eval: --trajectory-out takes one --track");
    core::check_output_file("--trajectory-out", request.trajectory_out.string());
  }
  if (!request.json_out.empty()) core::check_output_file("--json", request.json_out.string());
  const RlTracksLoaded loaded = load_rl_tracks(request.src);
  rlnode::ReplaySettings s = rlnode::settings_of(loaded.params);
  if (!request.noise_from.empty()) s.process_noise = rl_noise_from(request.noise_from, loaded.params.node_name);
  RlTrackEvalOutcome o;
  o.params_file = loaded.params.file;
  o.filter = loaded.params.filter;
  o.rows = score_rl_tracks(loaded, s, request.protocols, !request.trajectory_out.empty());
  pool_rows(o.rows, o);
  if (!request.trajectory_out.empty()) {
    write_rl_trajectory(
        request.trajectory_out, o.rows.front().scores.trajectory,
        fmt::format("robot_localization's {}_node ({}) on {}, every fix fused; the track's clock",
                    filters::rl::to_string(o.filter), o.params_file.string(), o.rows.front().track.string()));
  }
  if (!request.json_out.empty()) {
    nlohmann::json j = {
        {"params_file", o.params_file.string()},
        {"truth", {{"run", track_json_of(o.run)}, {"outages", track_json_of(o.outages)}}},
        {"fixes", {{"heldout", track_json_of(o.heldout_fixes)}, {"outages", track_json_of(o.outage_fixes)}}},
        {"tracks", nlohmann::json::array()}};
    for (const RlTrackRow& r : o.rows) j["tracks"].push_back(track_json_of(r));
    core::write_atomically(request.json_out, "JSON", j.dump(2) + "\n");
  }
  return o;
}

RlTrackTuneOutcome run_rl_track_tune(const RlTuneRequest& request, const RlTrackSource& src) {
  std::string why;
  if (!request.IsValid(&why)) throw core::Failure("tune: " + why);
  for (const auto& [flag, set] :
       {std::pair{"--until", request.until_s.has_value()}, std::pair{"--from", request.from_s.has_value()},
        std::pair{"--end", request.end_s.has_value()}}) {
    if (set)
      throw core::Failure(fmt::format("tune: {} cuts a bag; tracks are tuned whole (judge others with eval)",
                                      flag));
  }
  core::check_output_file("--config-out", request.config_out.string());
  core::check_output_file("--json", request.json_out.string());
  core::check_output_file("--config-out-ros1", request.config_out_ros1.string());
  if (!request.starts_out.empty()) core::check_output_dir("--starts-out", request.starts_out.string());
  const RlTracksLoaded loaded = load_rl_tracks(src);
  std::vector<const rlnode::Recording*> recs;
  for (const objectives::RlTrack& t : loaded.tracks) recs.push_back(&t.rec);
  const rlnode::ReplaySettings base = rlnode::settings_of(loaded.params);
  RlTrackTuneOutcome out;
  try {
    const objectives::RlObjective objective(recs, base, request.options);
    out.tune = search_rl(objective, request);
  } catch (const std::invalid_argument& e) {
    throw core::Failure(e.what());
  }
  RlTuneOutcome& o = out.tune;
  o.params_file = loaded.params.file;
  o.filter = loaded.params.filter;
  o.bag = src.tracks.front();
  o.tracks = src.tracks;
  for (const objectives::RlTrack& t : loaded.tracks) {
    o.duration_s += static_cast<double>(t.rec.end_ns - t.rec.start_ns) * 1e-9;
    for (const std::string& n : t.rec.notes) o.notes.push_back(t.file.string() + ": " + n);
  }
  o.baseline = base;
  out.before = score_rl_tracks(loaded, base, request.options);
  out.after = score_rl_tracks(loaded, o.tuned, request.options);
  for (const auto& [path, ros2] :
       {std::pair{request.config_out, !request.ros1_out}, std::pair{request.config_out_ros1, false}}) {
    if (!path.empty())
      write_tuned_params(path, loaded.params, o.tuned, std::nullopt, 0.0, ros2,
                         rl_tune_header(request, o, o.written));
  }
  if (!request.starts_out.empty()) {
    std::filesystem::create_directories(request.starts_out);
    for (std::size_t k = 0; k < o.starts.size(); ++k) {
      const auto path = request.starts_out / fmt::format("{}-seed{}.yaml",
                                                         filters::rl::to_string(o.starts[k].tuned.filter),
                                                         o.starts[k].seed);
      write_tuned_params(path, loaded.params, o.starts[k].tuned, std::nullopt, 0.0, !request.ros1_out,
                         rl_tune_header(request, o, k));
    }
  }
  if (!request.json_out.empty()) write_rl_tune_json(request.json_out, request, o);
  return out;
}

}  // namespace odotune::jobs
