#include <odotune/jobs/twist_calibrate_job.h>

#include <cmath>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <odotune/calibration/plausible_fit.h>
#include <odotune/core/failure.h>
#include <odotune/core/output_paths.h>
#include <odotune/formats/config_yaml.h>

namespace odotune::jobs {

namespace {

nlohmann::json num(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json score_json(const calibration::TwistScore& s) {
  return {{"pose_rmse_m", num(s.pose_rmse_m)},
          {"heading_rmse_rad", num(s.heading_rmse_rad)},
          {"samples", s.samples}};
}

nlohmann::json correction_json(tracks::OdometryInput input, const filters::TwistCorrection& c) {
  return {{"odometry", std::string(tracks::to_string(input))},
          {"scale_v", c.scale_v},
          {"scale_w", c.scale_w},
          {"delay_s", c.delay_s}};
}

std::string correction_text(const filters::TwistCorrection& c, const calibration::TwistCalibrationSummary* s) {
  const auto sd = [](double v) { return std::isfinite(v) ? fmt::format(" (± {:.4f})", v) : std::string(); };
  const std::string at = c.delay_s > 0.0 ? fmt::format("(t − {:.3f} s)", c.delay_s) : std::string("(t)");
  return fmt::format("v = {:.4f}{} · v_cmd{},  w = {:.4f}{} · w_cmd{}", c.scale_v, s ? sd(s->sd_scale_v) : "",
                     at, c.scale_w, s ? sd(s->sd_scale_w) : "", at);
}

std::string score_line(const std::string& name, const std::array<calibration::TwistScore, 2>& s) {
  const double gain = 100.0 * (s[0].pose_rmse_m - s[1].pose_rmse_m) / s[0].pose_rmse_m;
  return fmt::format("  {:<32} pose RMSE {:8.3f} → {:8.3f} m ({:+.1f} %)   heading RMSE {:.3f} → {:.3f} rad",
                     name, s[0].pose_rmse_m, s[1].pose_rmse_m, gain, s[0].heading_rmse_rad,
                     s[1].heading_rmse_rad);
}

// The calibration flags a body-velocity fit does not take, refused by name.
void refuse_wheel_flags(const CalibrateRequest& a, tracks::OdometryInput input) {
  const std::string method = a.method_name();
  if (!a.method || *a.method != calibration::CalibrationMethod::batch_pose)
    throw core::Failure(fmt::format(
        "--method {}: {} tracks are calibrated by --method batch (scales{} fitted to the "
        "ground truth or fixes); the online methods need wheel odometry",
        method, tracks::to_string(input), input == tracks::OdometryInput::commands ? " and a delay" : ""));
  for (const auto& [flag, given] :
       {std::pair{"--ext-from-gt", a.ext_from_gt_hz.has_value()},
        std::pair{"--ext-sigma-v", a.ext_sigma_v.has_value()},
        std::pair{"--ext-sigma-w", a.ext_sigma_w.has_value()},
        std::pair{"--init-radius-range", a.init_radius_range.has_value()},
        std::pair{"--init-wheel-base-range", a.init_wheel_base_range.has_value()},
        std::pair{"--tolerance", a.tolerance_pct.has_value()},
        std::pair{"--fit-start-heading", a.fit_start_heading}, std::pair{"--seed", a.seed.has_value()},
        std::pair{"--csv", !a.csv.empty()}, std::pair{"--figure", !a.figure.empty()},
        std::pair{"--controller-out", !a.controller.out.empty()},
        std::pair{"--paths-csv", !a.paths_csv.empty()}})
    if (given)
      throw core::Failure(fmt::format("{} does not apply to {} tracks (a fit of scales{}; wheel geometry only)",
                                      flag, tracks::to_string(input),
                                      input == tracks::OdometryInput::commands ? " and a delay" : ""));
}

// One track's row of the JSON: its dead reckoning as recorded and calibrated.
nlohmann::json track_json(const std::string& name, const std::string& file,
                          const std::array<calibration::TwistScore, 2>& s) {
  return {{"track", name}, {"file", file}, {"as_recorded", score_json(s[0])}, {"calibrated", score_json(s[1])}};
}

// Track k's odometry input (its own, or --input), or a Failure naming its file.
tracks::OdometryInput input_of(const CalibrateRequest& a, const std::vector<tracks::Track>& tracks,
                               std::size_t k) {
  try {
    return tracks::track_odometry_input(tracks[k], a.input);
  } catch (const std::invalid_argument& e) {
    throw core::Failure(fmt::format("{}: {}", a.tracks[k], e.what()));
  }
}

std::vector<const tracks::Track*> twist_pointers(const std::vector<tracks::Track>& tracks) {
  std::vector<const tracks::Track*> p;
  for (const tracks::Track& t : tracks) p.push_back(&t);
  return p;
}

}  // namespace

std::optional<tracks::OdometryInput> calibrate_body_input(const CalibrateRequest& a,
                                                          const std::vector<tracks::Track>& tracks) {
  std::optional<tracks::OdometryInput> kind;
  for (std::size_t k = 0; k < tracks.size(); ++k) {
    const tracks::OdometryInput in = input_of(a, tracks, k);
    if (kind && *kind != in)
      throw core::Failure(fmt::format("{}: {} odometry, {} gives {}: expected one kind for one calibration",
                                      a.tracks[k], tracks::to_string(in), a.tracks[0],
                                      tracks::to_string(*kind)));
    kind = in;
  }
  if (!kind || *kind == tracks::OdometryInput::wheels) return std::nullopt;
  return kind;
}

CalibrateOutcome run_twist_calibrate(const CalibrateRequest& a, const std::vector<tracks::Track>& tracks,
                                     tracks::OdometryInput input) {
  refuse_wheel_flags(a, input);
  calibration::TwistCalibrationOptions o;
  o.segment_s = a.segment_s.value_or(o.segment_s);
  CalibrateOutcome out;
  try {
    out.twist = calibration::calibrate_twist(twist_pointers(tracks), input, o);
  } catch (const std::invalid_argument& e) {
    throw core::Failure(fmt::format("calibrate: {}", e.what()));
  }
  const calibration::TwistCalibrationSummary& s = *out.twist;
  if (const auto why = calibration::implausible_twist(s.params))
    throw core::Failure(calibration::implausible_fit_message(*why));
  std::vector<std::string> names;
  for (const tracks::Track& t : tracks) {
    names.push_back(t.name());
    out.twist_scores.push_back({calibration::score_twist(t, {}), calibration::score_twist(t, s.params)});
  }
  std::vector<std::string>& l = out.summary;
  l.push_back(fmt::format(
      "calibrated the {} odometry of {} track{} ({}) by batch, in the pose domain:", tracks::to_string(input),
      tracks.size(), tracks.size() == 1 ? "" : "s", fmt::join(names, ", ")));
  l.push_back("  " + correction_text(s.params, &s));
  l.push_back("  " + s.residuals);
  l.push_back(fmt::format("  position RMSE over those segments: {:.3f} m (as recorded) → {:.3f} m{}",
                          s.initial_rmse_m, s.final_rmse_m,
                          s.converged ? "" : fmt::format(" (Ceres: {})", s.termination)));
  l.push_back("dead reckoning from each track's first ground-truth pose, as recorded → calibrated:");
  for (std::size_t k = 0; k < tracks.size(); ++k)
    if (out.twist_scores[k][0].samples > 0) l.push_back(score_line(names[k], out.twist_scores[k]));

  const std::string provenance = fmt::format(
      "calibrated by odotune calibrate: method batch ({} odometry)\ntracks: {}", tracks::to_string(input),
      fmt::join(a.tracks, ", "));
  nlohmann::json tracks_json = nlohmann::json::array();
  for (std::size_t k = 0; k < tracks.size(); ++k)
    tracks_json.push_back(track_json(names[k], a.tracks[k], out.twist_scores[k]));
  const nlohmann::json j = {{"method", "batch"},
                            {"calibration", correction_json(input, s.params)},
                            {"sd", {{"scale_v", num(s.sd_scale_v)}, {"scale_w", num(s.sd_scale_w)}}},
                            {"residuals", s.residuals},
                            {"initial_rmse_m", num(s.initial_rmse_m)},
                            {"final_rmse_m", num(s.final_rmse_m)},
                            {"converged", s.converged},
                            {"tracks", tracks_json}};
  if (!a.config_out.empty()) {
    formats::CalibrationFile file;
    file.odometry = input;
    file.twist = s.params;
    file.comment = provenance;
    formats::write_calibration_file(file, a.config_out);
  }
  if (!a.json.empty()) formats::write_file_atomically(a.json, j.dump(2) + "\n");
  return out;
}

ApplyOutcome run_twist_apply(const CalibrateRequest& a, const formats::CalibrationFile& file,
                             const std::vector<tracks::Track>& tracks) {
  ApplyOutcome out;
  out.twist = file.twist;
  std::vector<std::string>& l = out.summary;
  l.push_back(fmt::format("applied {} ({} odometry: {}) to {} track{}:", a.apply,
                          tracks::to_string(file.odometry), correction_text(file.twist, nullptr), tracks.size(),
                          tracks.size() == 1 ? "" : "s"));
  nlohmann::json tracks_json = nlohmann::json::array();
  for (std::size_t k = 0; k < tracks.size(); ++k) {
    const tracks::OdometryInput in = input_of(a, tracks, k);
    if (in != file.odometry)
      throw core::Failure(fmt::format("{}: {} odometry; the calibration file {} corrects {} odometry",
                                      a.tracks[k], tracks::to_string(in), a.apply,
                                      tracks::to_string(file.odometry)));
    if (!tracks[k].has_gt())
      throw core::Failure(
          fmt::format("{}: track '{}' has no ground truth (gt_x, gt_y, gt_theta); --apply scores dead "
                      "reckoning against it",
                      a.tracks[k], tracks[k].name()));
    out.twist_scores.push_back({calibration::score_twist(tracks[k], {}),
                                calibration::score_twist(tracks[k], file.twist)});
    l.push_back(score_line(tracks[k].name(), out.twist_scores.back()));
    tracks_json.push_back(track_json(tracks[k].name(), a.tracks[k], out.twist_scores.back()));
  }
  const nlohmann::json j = {{"calibration_file", a.apply},
                            {"calibration", correction_json(file.odometry, file.twist)},
                            {"tracks", tracks_json}};
  if (!a.json.empty()) formats::write_file_atomically(a.json, j.dump(2) + "\n");
  return out;
}

}  // namespace odotune::jobs
