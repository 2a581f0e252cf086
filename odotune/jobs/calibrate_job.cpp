#include <odotune/jobs/calibrate_job.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <odotune/calibration/calibration_ranges.h>
#include <odotune/calibration/plausible_fit.h>
#include <odotune/core/failure.h>
#include <odotune/core/output_paths.h>
#include <odotune/formats/calibration_yaml.h>
#include <odotune/formats/config_yaml.h>
#include <odotune/jobs/calibration_figure_data.h>
#include <odotune/jobs/calibration_summary.h>
#include <odotune/jobs/calibration_trace.h>
#include <odotune/jobs/twist_calibrate_job.h>
#include <odotune/results/calibration_figures.h>
#include <odotune/tracks/track_io.h>

namespace odotune::jobs {

namespace {

using filters::OdometryParams;
using Range = filters::PfCalibratorParams::Range;

// The wheelchair the PF/DKF defaults were tuned for (PfCalibratorParams).
constexpr double kPaperRadiusM = 0.32;
constexpr double kPaperWheelBaseM = 0.65;
// External velocities for --apply on tracks without v_ext (unused by the
// dead reckoning it scores; the V/W errors it also reports compare at them).
constexpr double kApplyExtRateHz = 10.0;

// "LO,HI" in metres with 0 < LO < HI.
Range parse_range(const std::string& flag, const std::string& text) {
  const auto comma = text.find(',');
  Range r;
  std::size_t used_lo = 0, used_hi = 0;
  try {
    if (comma == std::string::npos) throw std::invalid_argument("no comma");
    const std::string lo = text.substr(0, comma), hi = text.substr(comma + 1);
    r.lo = std::stod(lo, &used_lo);
    r.hi = std::stod(hi, &used_hi);
    if (used_lo != lo.size() || used_hi != hi.size()) throw std::invalid_argument("trailing text");
  } catch (const std::exception&) {
    throw core::Failure(fmt::format("{} '{}': expected LO,HI in metres, e.g. 0.30,0.34", flag, text));
  }
  if (!(std::isfinite(r.lo) && std::isfinite(r.hi) && r.lo > 0.0 && r.lo < r.hi))
    throw core::Failure(fmt::format("{} '{}': expected 0 < LO < HI [m]", flag, text));
  return r;
}

std::vector<calibration::CalibrationInput> build_inputs(const CalibrateRequest& a, bool apply,
                                                        const std::vector<tracks::Track>& tracks) {
  const std::vector<std::string>& files = a.tracks;
  // The pose fit needs no external velocity (it fits to the ground truth or
  // the fixes), nor does online-pose (the fixes); nor do none and --apply,
  // which score dead reckoning.
  const calibration::CalibrationMethod method = a.method_or_default();
  const bool no_velocity_method = !apply && (method == calibration::CalibrationMethod::batch_pose ||
                                             method == calibration::CalibrationMethod::online_pose ||
                                             method == calibration::CalibrationMethod::none);
  std::vector<calibration::CalibrationInput> inputs;
  for (std::size_t k = 0; k < tracks.size(); ++k) {
    calibration::CalibrationInputOptions o;
    o.ext_from_gt_rate_hz = a.ext_from_gt_hz.value_or(0.0);
    // --ext-sigma-v/-w given: those, not the noise estimated from the ground truth's jitter.
    const double sigma_v = a.ext_sigma_v.value_or(0.0), sigma_w = a.ext_sigma_w.value_or(0.0);
    o.estimate_ext_noise = !(sigma_v > 0.0 || sigma_w > 0.0);
    if (sigma_v > 0.0) o.default_v_var = sigma_v * sigma_v;
    if (sigma_w > 0.0) o.default_w_var = sigma_w * sigma_w;
    const tracks::Track& tr = tracks[k];
    const bool has_ext = tr.has(tracks::Col::v_ext) && tr.has(tracks::Col::w_ext);
    if (apply && o.ext_from_gt_rate_hz <= 0.0 && !has_ext && tr.has_gt())
      o.ext_from_gt_rate_hz = kApplyExtRateHz;
    o.require_velocity_samples = !(no_velocity_method || apply);
    std::string why;
    if (!o.IsValid(&why))
      throw core::Failure(fmt::format("--ext-from-gt {}: {}", a.ext_from_gt_hz.value_or(0.0), why));
    if (o.ext_from_gt_rate_hz <= 0.0 && !has_ext && o.require_velocity_samples)
      throw core::Failure(
          tr.has_gt() ? fmt::format("{}: track '{}' has no external velocities (v_ext, w_ext); expected "
                                    "them, or --ext-from-gt HZ to derive them from its ground truth",
                                    files[k], tr.name())
                      : fmt::format("{}: track '{}' has no external velocities (v_ext, w_ext) and no "
                                    "ground truth (gt_x, gt_y) to derive them from; expected either",
                                    files[k], tr.name()));
    try {
      inputs.push_back(calibration::build_calibration_input(tracks[k], o));
    } catch (const std::invalid_argument& e) {
      throw core::Failure(fmt::format("{}: {}", files[k], e.what()));
    }
    if (apply && !inputs.back().has_gt)
      throw core::Failure(
          fmt::format("{}: track '{}' has no ground truth (gt_x, gt_y, gt_theta); --apply scores "
                      "dead reckoning against it",
                      files[k], inputs.back().track_name));
  }
  return inputs;
}

// Several tracks are calibrated as one robot: their nominal parameters must agree.
void check_same_robot(const std::vector<calibration::CalibrationInput>& inputs,
                      const std::vector<std::string>& files) {
  const auto differs = [](double a, double b) {
    return std::abs(a - b) > 1e-9 * std::max(std::abs(a), std::abs(b));
  };
  for (std::size_t k = 1; k < inputs.size(); ++k) {
    const OdometryParams &a = inputs[0].nominal, &b = inputs[k].nominal;
    if (differs(a.wheel_radius_left_m, b.wheel_radius_left_m) ||
        differs(a.wheel_radius_right_m, b.wheel_radius_right_m) || differs(a.wheel_base_m, b.wheel_base_m))
      throw core::Failure(fmt::format(
          "{}: nominal R_L/R_R/D = {}/{}/{} m differ from {}'s {}/{}/{} m; expected tracks of one robot",
          files[k], b.wheel_radius_left_m, b.wheel_radius_right_m, b.wheel_base_m, files[0],
          a.wheel_radius_left_m, a.wheel_radius_right_m, a.wheel_base_m));
  }
}

// The flags that apply to one kind of method only, refused for the others.
void check_method_flags(const CalibrateRequest& a, calibration::CalibrationMethod m,
                        const std::string& method) {
  if ((a.segment_s.has_value() || a.fit_start_heading) && m != calibration::CalibrationMethod::batch_pose)
    throw core::Failure(fmt::format(
        "--segment and --fit-start-heading apply to --method batch-pose only (got --method {})", method));
  const bool pf = m == calibration::CalibrationMethod::pf || m == calibration::CalibrationMethod::adaptive_pf;
  for (const auto& [flag, given] :
       {std::pair{"--resampler", a.resampler.has_value()}, std::pair{"--policy", a.policy.has_value()},
        std::pair{"--particles", a.particles.has_value()},
        std::pair{"--pf-evolution", a.pf_evolution.has_value()},
        std::pair{"--pf-memory", a.pf_memory_s.has_value()}})
    if (given && !pf)
      throw core::Failure(fmt::format("{} applies to --method pf and adaptive-pf only (got --method {})", flag,
                                      method));
  for (const auto& [flag, given] :
       {std::pair{"--start", a.start.has_value()}, std::pair{"--fix-sigma-m", a.fix_sigma_m.has_value()},
        std::pair{"--pose-memory-m", a.pose_memory_m.has_value()}})
    if (given && m != calibration::CalibrationMethod::online_pose)
      throw core::Failure(fmt::format("{} applies to --method online-pose only (got --method {})", flag,
                                      method));
}

// The online pose-domain calibrator: starts at the nominal geometry; the
// flags over its defaults.
void make_online_pose_options(const CalibrateRequest& a, const OdometryParams& nominal,
                              calibration::OnlinePoseOptions& o) {
  o.filter.initial = nominal;
  if (a.start) o.start = *a.start;
  if (a.fix_sigma_m) {
    if (!(std::isfinite(*a.fix_sigma_m) && *a.fix_sigma_m > 0.0))
      throw core::Failure(fmt::format("--fix-sigma-m {}: expected a finite sd > 0 [m]", *a.fix_sigma_m));
    o.fix_sd_m = *a.fix_sigma_m;
  }
  if (a.pose_memory_m) {
    if (!(std::isfinite(*a.pose_memory_m) && *a.pose_memory_m > 0.0))
      throw core::Failure(fmt::format("--pose-memory-m {}: expected a finite distance > 0 [m]",
                                      *a.pose_memory_m));
    o.min_memory_m = *a.pose_memory_m;
  }
}

// The particle filter's flags over its defaults.
void apply_pf_flags(const CalibrateRequest& a, filters::PfCalibratorParams& pf) {
  if (a.resampler) pf.resampler = *a.resampler;
  if (a.policy) pf.policy = *a.policy;
  if (a.particles.value_or(0) > 0) pf.particles = *a.particles;
  if (a.pf_evolution) pf.evolution = *a.pf_evolution;
  if (a.pf_memory_s.value_or(0.0) > 0.0) {
    pf.evidence.min_memory_s = *a.pf_memory_s;
    pf.evidence.max_memory_s = std::max(pf.evidence.max_memory_s, *a.pf_memory_s);
  }
  if (a.seed) pf.seed = *a.seed;
  pf.threads = a.threads;
}

formats::CalibrationRunInfo make_options(const CalibrateRequest& a,
                                         const std::vector<calibration::CalibrationInput>& inputs) {
  formats::CalibrationRunInfo info;
  info.track_files = a.tracks;
  info.ext_from_gt_rate_hz = a.ext_from_gt_hz.value_or(0.0);
  calibration::CalibrationOptions& o = info.options;
  o.method = a.method_or_default();
  check_method_flags(a, o.method, a.method_name());
  o.pose.segment_s = a.segment_s.value_or(0.0);
  o.pose.fit_start_heading = a.fit_start_heading;
  const OdometryParams& nom = inputs.front().nominal;
  make_online_pose_options(a, nom, o.online_pose);
  const double r_nom = 0.5 * (nom.wheel_radius_left_m + nom.wheel_radius_right_m);
  const double r_scale = r_nom / kPaperRadiusM, d_scale = nom.wheel_base_m / kPaperWheelBaseM;

  const calibration::CalibrationRanges ranges = calibration::default_calibration_ranges(nom);
  Range r_left = ranges.wheel_radius_left_m;
  Range r_right = ranges.wheel_radius_right_m;
  Range base = ranges.wheel_base_m;
  const std::string radius_range = a.init_radius_range.value_or(""),
                    base_range = a.init_wheel_base_range.value_or("");
  if (!radius_range.empty()) r_left = r_right = parse_range("--init-radius-range", radius_range);
  if (!base_range.empty()) base = parse_range("--init-wheel-base-range", base_range);
  info.init_radius_m = {std::min(r_left.lo, r_right.lo), std::max(r_left.hi, r_right.hi)};
  info.init_wheel_base_m = base;

  o.pf = o.method == calibration::CalibrationMethod::adaptive_pf
             ? filters::PfCalibratorParams::adaptive_defaults()
             : filters::PfCalibratorParams{};
  o.pf.wheel_radius_left_m = r_left;
  o.pf.wheel_radius_right_m = r_right;
  o.pf.wheel_base_m = base;
  o.pf.random_walk_sigma_m *= r_scale;
  o.pf.alpha *= r_scale;
  o.pf.dispersion_per_particle_m *= r_scale;
  o.pf.min_random_walk_sigma_m *= r_scale;
  apply_pf_flags(a, o.pf);

  const auto centre = [](const Range& r) { return 0.5 * (r.lo + r.hi); };
  const auto uniform_sd = [](const Range& r) { return (r.hi - r.lo) / std::sqrt(12.0); };
  o.dkf.initial = {centre(r_left), centre(r_right), centre(base)};
  o.dkf.initial_sd_radius_m = std::max(uniform_sd(r_left), uniform_sd(r_right));
  o.dkf.initial_sd_wheel_base_m = uniform_sd(base);
  o.dkf.radius_walk_m_per_sqrt_s *= r_scale;
  o.dkf.wheel_base_walk_m_per_sqrt_s *= d_scale;

  if (a.tolerance_pct) {
    const double tolerance_pct = *a.tolerance_pct;
    if (!(std::isfinite(tolerance_pct) && tolerance_pct > 0.0 && tolerance_pct < 100.0))
      throw core::Failure(fmt::format("--tolerance {}: expected a percentage in (0, 100)", tolerance_pct));
    o.convergence_tolerance = tolerance_pct / 100.0;
  }
  std::string why;
  if (!o.IsValid(&why)) throw core::Failure(fmt::format("--method {}: {}", a.method_name(), why));
  return info;
}

// Calls `f` (when set) on leaving the scope, normally or by an exception.
struct OnExit {
  const std::function<void()>& f;
  ~OnExit() {
    if (f) f();
  }
};

// Where a calibration file's numbers come from: the method, and the PF's seed.
std::string provenance_line(const CalibrateRequest& a, const CalibrateOutcome& out) {
  const bool pf = out.result.method == calibration::CalibrationMethod::pf ||
                  out.result.method == calibration::CalibrationMethod::adaptive_pf;
  return fmt::format("calibrated by odotune calibrate: method {}{}", a.method_name(),
                     pf ? fmt::format(", seed {}", out.info.options.pf.seed) : "");
}

// --controller-out: the final estimate as the controller's parameters.
std::string write_calibrate_controller(const CalibrateRequest& a, const CalibrateOutcome& out,
                                       const formats::ControllerOptions& options) {
  return write_controller_file(a.controller, options,
                               calibration_controller_geometry(a.controller, out.result, out.nominal,
                                                               out.inputs.front().nominal,
                                                               provenance_line(a, out), a.tracks));
}

}  // namespace

CalibrateOutcome run_calibrate(const CalibrateRequest& a, const CalibrateHooks& hooks) {
  for (const auto& [flag, path] : {std::pair{"--json", &a.json}, std::pair{"--csv", &a.csv},
                                   std::pair{"--figure", &a.figure}, std::pair{"--config-out", &a.config_out}})
    core::check_output_dir(flag, *path);
  const formats::ControllerOptions controller = check_controller_request(a.controller, true);
  if (!a.paths_csv.empty())
    throw core::Failure("--paths-csv applies to --apply only (the paths of a calibration file)");
  const std::vector<tracks::Track> tracks = tracks::load_tracks(a.tracks);
  if (const auto body = calibrate_body_input(a, tracks)) return run_twist_calibrate(a, tracks, *body);
  if (a.input && *a.input != tracks::OdometryInput::wheels)
    throw core::Failure(fmt::format("--input {}: the tracks have wheel odometry", tracks::to_string(*a.input)));
  CalibrateOutcome out;
  out.inputs = build_inputs(a, false, tracks);
  check_same_robot(out.inputs, a.tracks);
  out.info = make_options(a, out.inputs);
  std::vector<const calibration::CalibrationInput*> ptrs;
  std::size_t samples = 0;
  for (const auto& in : out.inputs) ptrs.push_back(&in), samples += in.samples.size();

  if (hooks.on_start)
    hooks.on_start(fmt::format("calibrating with {} over {} samples…", a.method_name(), samples));
  {
    const OnExit end{hooks.on_end};
    try {
      out.result = calibration::run_calibration(ptrs, out.info.options);
    } catch (const std::invalid_argument& e) {
      throw core::Failure(fmt::format("calibrate: {}", e.what()));
    }
  }
  if (const auto why = calibration::implausible_geometry(out.result.final_params, out.inputs.front().nominal))
    throw core::Failure(calibration::implausible_fit_message(*why));

  for (const auto& in : out.inputs) out.nominal.push_back(calibration::score_fixed_params(in, in.nominal));
  out.summary = calibration_summary_lines(out.result, out.inputs, out.nominal, out.info);
  const std::string json_text = formats::calibration_json(out.result, ptrs, out.nominal, out.info).dump(2) +
                                "\n";
  CalibrationTraceTable table;
  try {
    table = build_trace_table(out.result, ptrs);
  } catch (const std::invalid_argument& e) {
    throw core::Failure(fmt::format("calibrate: {}", e.what()));
  }

  // Outputs: the figure first (gnuplot is the likeliest to fail), the JSON last.
  if (!a.figure.empty()) {
    std::vector<std::string> names;
    for (const auto& in : out.inputs) names.push_back(in.track_name);
    try {
      results::calibration_estimates_figure(
          a.figure, calibration_figure_data(table, fmt::format("{}: {} calibration", fmt::join(names, ", "),
                                                               a.method_name())));
    } catch (const std::exception& e) {
      throw core::Failure(fmt::format("--figure {}: {}", a.figure, e.what()));
    }
  }
  if (!a.csv.empty()) formats::write_file_atomically(a.csv, trace_csv(table));
  if (!a.config_out.empty()) {
    formats::CalibrationFile file;
    file.params = out.result.final_params;
    file.comment = fmt::format("{}\ntracks: {}", provenance_line(a, out), fmt::join(a.tracks, ", "));
    formats::write_calibration_file(file, a.config_out);
  }
  if (!a.controller.out.empty()) out.controller_line = write_calibrate_controller(a, out, controller);
  if (!a.json.empty()) formats::write_file_atomically(a.json, json_text);
  return out;
}

ApplyOutcome run_calibrate_apply(const CalibrateRequest& a) {
  for (const auto& [flag, given] :
       {std::pair{"--method", a.method.has_value()}, std::pair{"--resampler", a.resampler.has_value()},
        std::pair{"--policy", a.policy.has_value()}, std::pair{"--particles", a.particles.has_value()},
        std::pair{"--seed", a.seed.has_value()},
        std::pair{"--init-radius-range", a.init_radius_range.has_value()},
        std::pair{"--init-wheel-base-range", a.init_wheel_base_range.has_value()},
        std::pair{"--tolerance", a.tolerance_pct.has_value()}, std::pair{"--csv", !a.csv.empty()},
        std::pair{"--figure", !a.figure.empty()}, std::pair{"--config-out", !a.config_out.empty()}})
    if (given)
      throw core::Failure(fmt::format("{} does not combine with --apply (which replays a calibration file)",
                                      flag));
  refuse_controller_flags(a.controller, "--apply (which replays a calibration file; the calibrate run that "
                                        "makes one writes the controller file)");
  core::check_output_dir("--json", a.json);
  core::check_output_dir("--paths-csv", a.paths_csv);
  const formats::CalibrationFile cal = formats::read_calibration_file(a.apply);
  const std::vector<tracks::Track> tracks = tracks::load_tracks(a.tracks);
  if (cal.odometry != tracks::OdometryInput::wheels) return run_twist_apply(a, cal, tracks);
  const std::vector<calibration::CalibrationInput> inputs = build_inputs(a, true, tracks);
  ApplyOutcome out;
  out.params = cal.params;
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    formats::AppliedTrack t;
    t.file = a.tracks[k];
    t.nominal_params = inputs[k].nominal;
    t.nominal = calibration::score_fixed_params(inputs[k], inputs[k].nominal);
    t.calibrated = calibration::score_fixed_params(inputs[k], cal.params);
    out.tracks.push_back(std::move(t));
  }
  const std::string json_text = formats::apply_json(a.apply, cal.params, out.tracks).dump(2) + "\n";
  if (!a.paths_csv.empty()) {
    std::string csv = "track,t_s,gt_x_m,gt_y_m,nominal_x_m,nominal_y_m,calibrated_x_m,calibrated_y_m\n";
    for (const calibration::CalibrationInput& in : inputs) {
      const calibration::DeadReckonedPath nom = calibration::dead_reckoned_path(in, in.nominal);
      const calibration::DeadReckonedPath calp = calibration::dead_reckoned_path(in, cal.params);
      for (std::size_t i = 0; i < nom.t.size(); ++i)
        csv += fmt::format("{},{:.4f},{:.5f},{:.5f},{:.5f},{:.5f},{:.5f},{:.5f}\n", in.track_name, nom.t[i],
                           nom.gt_x[i], nom.gt_y[i], nom.x[i], nom.y[i], calp.x[i], calp.y[i]);
    }
    formats::write_file_atomically(a.paths_csv, csv);
  }
  if (!a.json.empty()) formats::write_file_atomically(a.json, json_text);
  out.summary = apply_summary_lines(a.apply, cal.params, out.tracks);
  return out;
}

}  // namespace odotune::jobs
