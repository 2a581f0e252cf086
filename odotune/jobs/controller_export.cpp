#include <odotune/jobs/controller_export.h>

#include <cmath>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <odotune/core/failure.h>
#include <odotune/core/output_paths.h>
#include <odotune/diagnose/diagnosis_summary.h>

namespace odotune::jobs {

namespace {

using filters::OdometryParams;

// The flags given, in the order a refusal names them.
std::vector<std::pair<const char*, bool>> given_flags(const ControllerRequest& r) {
  return {{"--controller-out", !r.out.empty()},
          {"--controller", r.kind.has_value()},
          {"--controller-form", r.form.has_value()},
          {"--controller-name", r.name.has_value()},
          {"--nominal-wheel-radius-m", r.nominal_wheel_radius_m.has_value()},
          {"--nominal-wheel-base-m", r.nominal_wheel_base_m.has_value()}};
}

void check_length(const char* flag, const std::optional<double>& v) {
  if (v && !(std::isfinite(*v) && *v > 0.0))
    throw core::Failure(fmt::format("{} {}: expected a finite length > 0 [m]", flag, *v));
}

// The nominal the multipliers refer to: the track's, with the overrides.
OdometryParams controller_nominal(const ControllerRequest& r, const OdometryParams& track,
                                  std::string* source) {
  OdometryParams n = track;
  if (r.nominal_wheel_radius_m) n.wheel_radius_left_m = n.wheel_radius_right_m = *r.nominal_wheel_radius_m;
  if (r.nominal_wheel_base_m) n.wheel_base_m = *r.nominal_wheel_base_m;
  const bool radius = r.nominal_wheel_radius_m.has_value(), base = r.nominal_wheel_base_m.has_value();
  *source = radius && base ? "radius and wheel base given on the command line"
            : radius ? "radius given on the command line, wheel base from the first track's robot.* metadata"
            : base   ? "wheel base given on the command line, radii from the first track's robot.* metadata"
                     : "the first track's robot.* metadata";
  return n;
}

std::string pct(const diagnose::BeforeAfter& h) {
  return fmt::format("{:+.0f} %", 100.0 * (h.after_pos_rmse_m - h.before_pos_rmse_m) / h.before_pos_rmse_m);
}

bool has_numbers(const diagnose::BeforeAfter& h) {
  return std::isfinite(h.before_pos_rmse_m) && std::isfinite(h.after_pos_rmse_m) && h.before_pos_rmse_m > 0.0;
}

}  // namespace

bool ControllerRequest::any_given() const {
  for (const auto& [flag, given] : given_flags(*this))
    if (given) return true;
  return false;
}

formats::ControllerOptions check_controller_request(const ControllerRequest& r, bool nominal_flags_allowed) {
  formats::ControllerOptions o;
  if (!r.any_given()) return o;
  if (!nominal_flags_allowed && (r.nominal_wheel_radius_m || r.nominal_wheel_base_m))
    throw core::Failure(
        fmt::format("{} applies to calibrate only (diagnose corrects the track's own nominal robot)",
                    r.nominal_wheel_radius_m ? "--nominal-wheel-radius-m" : "--nominal-wheel-base-m"));
  if (r.out.empty())
    for (const auto& [flag, given] : given_flags(r))
      if (given) throw core::Failure(fmt::format("{} needs --controller-out FILE (the file to write)", flag));
  if (!r.kind) throw core::Failure("--controller-out needs --controller ros2_control, ros1 or gazebo");
  if (!formats::parse_controller_kind(*r.kind, &o.kind))
    throw core::Failure(fmt::format("--controller '{}': expected ros2_control, ros1 or gazebo", *r.kind));
  if (o.kind == formats::ControllerKind::gazebo && (r.form || r.name))
    throw core::Failure(
        fmt::format("{} applies to --controller ros2_control and ros1 only (Gazebo's DiffDrive has no "
                    "multipliers and no controller name; it gets the absolute geometry)",
                    r.form ? "--controller-form" : "--controller-name"));
  if (r.form && !formats::parse_controller_form(*r.form, &o.form))
    throw core::Failure(fmt::format("--controller-form '{}': expected multipliers or absolute", *r.form));
  if (r.name) o.controller_name = *r.name;
  if (!o.IsValid(nullptr))
    throw core::Failure(
        fmt::format("--controller-name '{}': not a ROS name, expected letters, digits, '_' and '/', not "
                    "starting with a digit",
                    o.controller_name));
  check_length("--nominal-wheel-radius-m", r.nominal_wheel_radius_m);
  check_length("--nominal-wheel-base-m", r.nominal_wheel_base_m);
  core::check_output_file("--controller-out", r.out);
  return o;
}

void refuse_controller_flags(const ControllerRequest& r, const std::string& context) {
  for (const auto& [flag, given] : given_flags(r))
    if (given) throw core::Failure(fmt::format("{} does not combine with {}", flag, context));
}

formats::ControllerGeometry calibration_controller_geometry(
    const ControllerRequest& r, const calibration::CalibrationResult& result,
    const std::vector<calibration::TrackCalibrationScore>& nominal_scores, const OdometryParams& track_nominal,
    const std::string& method_line, const std::vector<std::string>& track_files) {
  formats::ControllerGeometry g;
  g.calibrated = result.final_params;
  g.nominal = controller_nominal(r, track_nominal, &g.nominal_source);
  g.provenance = {method_line, fmt::format("tracks: {}", fmt::join(track_files, ", "))};
  if (!result.trace.estimate.empty()) {
    const filters::CalibEstimate& e = result.trace.estimate.back();
    if (e.sd_radius_left_m > 0.0 || e.sd_radius_right_m > 0.0 || e.sd_wheel_base_m > 0.0)
      g.provenance.push_back(fmt::format("sd of the final estimate: R_L {:.2g} m, R_R {:.2g} m, D {:.2g} m",
                                         e.sd_radius_left_m, e.sd_radius_right_m, e.sd_wheel_base_m));
  }
  for (std::size_t k = 0; k < result.tracks.size() && k < nominal_scores.size(); ++k) {
    const double before = nominal_scores[k].pose_rmse_m, after = result.tracks[k].pose_rmse_m;
    if (std::isfinite(before) && std::isfinite(after))
      g.provenance.push_back(fmt::format("dead-reckoning pose RMSE on {} (a calibrated track, not held out): "
                                         "nominal {:.4f} m, calibrated {:.4f} m",
                                         result.tracks[k].track, before, after));
  }
  g.provenance.push_back("not checked on held-out runs here: replay the calibration on other runs with "
                         "odotune calibrate's apply mode");
  return g;
}

filters::OdometryParams diagnosis_track_nominal(const diagnose::DiagInput& in, const std::string& file) {
  OdometryParams n;
  n.wheel_radius_left_m = in.radius_l_m;
  n.wheel_radius_right_m = in.radius_r_m;
  n.wheel_base_m = in.wheel_base_m;
  std::string why;
  if (!n.IsValid(&why))
    throw core::Failure(
        fmt::format("--controller-out: {}: track '{}' states no nominal wheel geometry (robot.* "
                    "metadata: {}); a controller file needs it",
                    file, in.track_name, why));
  return n;
}

std::optional<formats::ControllerGeometry> diagnosis_controller_geometry(
    const diagnose::Diagnosis& d, const diagnose::PooledDiagnosis* pooled, const OdometryParams& track_nominal,
    const std::vector<std::string>& fit_files, const std::vector<std::string>& heldout_files) {
  formats::ControllerGeometry g;
  g.nominal = g.calibrated = track_nominal;
  g.nominal_source = "the track's robot.* metadata";
  g.provenance = {"corrected by odotune diagnose: the nominal robot × the fitted scales",
                  fmt::format("tracks: {}", fmt::join(fit_files, ", "))};
  if (!heldout_files.empty())
    g.provenance.push_back(fmt::format("held-out recordings (never fitted): {}",
                                       fmt::join(heldout_files, ", ")));
  std::vector<std::string> used, others;
  for (const diagnose::Finding& f : d.findings) {
    if (f.is(diagnose::Effect::radius_error)) {
      g.calibrated.wheel_radius_left_m *= f.param("scale_l");
      g.calibrated.wheel_radius_right_m *= f.param("scale_r");
    } else if (f.is(diagnose::Effect::wheel_base_error)) {
      g.calibrated.wheel_base_m *= f.param("scale");
    } else {
      others.emplace_back(f.name());
      continue;
    }
    used.emplace_back(f.name());
    g.provenance.push_back(fmt::format("{}: {} (explains {:.0f} % of the nominal error)", f.name(),
                                       diagnose::finding_size(f), 100.0 * f.explains));
    if (has_numbers(f.heldout))
      g.heldout.push_back(fmt::format("held-out position error without → with {}: {:.4f} m → {:.4f} m ({})",
                                      f.name(), f.heldout.before_pos_rmse_m, f.heldout.after_pos_rmse_m,
                                      pct(f.heldout)));
    if (f.heldout_test)
      g.heldout.push_back(fmt::format("{} on the held-out recordings: {}{}", f.name(),
                                      describe(*f.heldout_test),
                                      f.heldout_test->proven ? ", proven" : ", not proven"));
  }
  if (used.empty()) return std::nullopt;
  if (!others.empty())
    g.provenance.push_back(fmt::format("other findings, not in this file: {}", fmt::join(others, ", ")));
  if (has_numbers(d.heldout))
    g.heldout.push_back(
        fmt::format("held-out position error, nominal → the whole chosen model: {:.4f} m → {:.4f} m "
                    "({})",
                    d.heldout.before_pos_rmse_m, d.heldout.after_pos_rmse_m, pct(d.heldout)));
  if (pooled && pooled->heldout_recordings)
    g.heldout.push_back(
        fmt::format("held-out recordings, nominal → the pooled model: {:.4f} m → {:.4f} m; {}, {}",
                    pooled->heldout_test.error.before_pos_rmse_m, pooled->heldout_test.error.after_pos_rmse_m,
                    describe(pooled->heldout_test), pooled->heldout_test.proven ? "proven" : "not proven"));
  return g;
}

std::string write_controller_file(const ControllerRequest& r, const formats::ControllerOptions& o,
                                  const formats::ControllerGeometry& g) {
  formats::write_controller_config(g, o, r.out);
  if (o.kind == formats::ControllerKind::gazebo) {
    const formats::ControllerValues v = formats::controller_values(g, formats::ControllerForm::absolute);
    const double diff = g.calibrated.wheel_radius_right_m - g.calibrated.wheel_radius_left_m;
    return fmt::format(
        "controller: {} (gazebo DiffDrive: wheel_radius {:.7f} m, the mean; R_R - R_L = {:+.7f} m "
        "cannot be represented; wheel_separation {:.7f} m)",
        r.out, v.wheel_radius_m, diff, v.wheel_separation_m);
  }
  const formats::ControllerValues v = formats::controller_values(g, o.form);
  return fmt::format("controller: {} ({} {}, {} form: wheel_radius {:.7f} m × left {:.6f}, right {:.6f}; "
                     "wheel_separation {:.7f} m × {:.6f})",
                     r.out, formats::to_string(o.kind), o.controller_name, formats::to_string(o.form),
                     v.wheel_radius_m, v.left_wheel_radius_multiplier, v.right_wheel_radius_multiplier,
                     v.wheel_separation_m, v.wheel_separation_multiplier);
}

}  // namespace odotune::jobs
