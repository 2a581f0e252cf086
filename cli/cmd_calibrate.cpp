// odotune calibrate: online (or batch) calibration of the odometry
// parameters R_R, R_L and D from wheel rates and external body velocities
// (Fariña, Toledo & Acosta, RA-L 2026; objectives/calibration_run.h), and
// the replay of a calibration on held-out tracks (--apply).
//
// Initial guesses (a choice of this command, not the paper's): the PF draws
// each radius uniformly from its track's nominal ±5 % and the wheel base
// from nominal ±15 %, so any robot size works; for the paper's wheelchair
// (R = 0.32 m, D = 0.65 m) these are 0.304–0.336 m and 0.5525–0.7475 m,
// the paper's 0.305–0.335 m and 0.55–0.75 m to within 2.5 mm. The DKF
// starts at the range's centre with sd = width/√12 (the uniform's sd). The
// calibrators' length-valued tuning constants (PF random walk σ, adaptive α
// and its σ floor, particles per dispersion, DKF random walks) are the paper's wheelchair
// values scaled by R_nom/0.32 m (and D_nom/0.65 m for the DKF's wheel-base
// walk), so a robot with 5 cm wheels gets the same relative noise.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "jobs/calibration_figure_data.h"
#include "formats/calibration_json.h"
#include "objectives/calibration_ranges.h"
#include "jobs/calibration_trace.h"
#include "formats/calibration_yaml.h"
#include "cli/commands.h"
#include "formats/config_yaml.h"
#include "core/failure.h"
#include "core/output_paths.h"
#include "cli/output.h"
#include "tracks/track_io.h"
#include "cli/progress.h"
#include "objectives/calibration_input.h"
#include "objectives/calibration_run.h"
#include "results/calibration_figures.h"

namespace odotune::cli {

namespace {

namespace fs = std::filesystem;
using filters::OdometryParams;
using Range = filters::PfCalibratorParams::Range;

// The wheelchair the PF/DKF defaults were tuned for (PfCalibratorParams).
constexpr double kPaperRadiusM = 0.32;
constexpr double kPaperWheelBaseM = 0.65;
// External velocities for --apply on tracks without v_ext (unused by the
// dead reckoning it scores, but build_calibration_input wants some).
constexpr double kApplyExtRateHz = 10.0;

struct CalibrateArgs {
  std::vector<std::string> tracks;
  std::string method = "adaptive-pf";
  std::string resampler, policy;
  std::uint64_t seed = 1;
  int particles = 0;
  int threads = 0;
  double ext_from_gt_hz = 0.0;
  double ext_sigma_v = 0.0;   // [m/s]; 0: the track's v_ext_var, else 0.02
  double ext_sigma_w = 0.0;   // [rad/s]; 0: the track's w_ext_var, else 0.02
  std::string init_radius_range, init_wheel_base_range;
  double tolerance_pct = 0.5;
  std::string json, csv, figure, config_out, apply;
  // Which options were given (filled at registration).
  CLI::Option *method_opt = nullptr, *resampler_opt = nullptr, *policy_opt = nullptr,
              *particles_opt = nullptr, *seed_opt = nullptr, *radius_opt = nullptr, *base_opt = nullptr,
              *tolerance_opt = nullptr;
};

bool given(const CLI::Option* o) { return o != nullptr && o->count() > 0; }

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
    throw Failure(fmt::format("{} '{}': expected LO,HI in metres, e.g. 0.30,0.34", flag, text));
  }
  if (!(std::isfinite(r.lo) && std::isfinite(r.hi) && r.lo > 0.0 && r.lo < r.hi))
    throw Failure(fmt::format("{} '{}': expected 0 < LO < HI [m]", flag, text));
  return r;
}


std::vector<CalibrationInput> build_inputs(const std::vector<std::string>& files, double ext_from_gt_hz,
                                           bool apply, double ext_sigma_v_m_s, double ext_sigma_w_rad_s) {
  const std::vector<Track> tracks = load_tracks(files);
  std::vector<CalibrationInput> inputs;
  for (std::size_t k = 0; k < tracks.size(); ++k) {
    CalibrationInputOptions o;
    o.ext_from_gt_rate_hz = ext_from_gt_hz;
    if (ext_sigma_v_m_s > 0.0) o.default_v_var = ext_sigma_v_m_s * ext_sigma_v_m_s;
    if (ext_sigma_w_rad_s > 0.0) o.default_w_var = ext_sigma_w_rad_s * ext_sigma_w_rad_s;
    const Track& tr = tracks[k];
    const bool has_ext = tr.has(Col::v_ext) && tr.has(Col::w_ext);
    if (apply && o.ext_from_gt_rate_hz <= 0.0 && !has_ext && tr.has_gt()) o.ext_from_gt_rate_hz = kApplyExtRateHz;
    std::string why;
    if (!o.IsValid(&why)) throw Failure(fmt::format("--ext-from-gt {}: {}", ext_from_gt_hz, why));
    if (o.ext_from_gt_rate_hz <= 0.0 && !has_ext)
      throw Failure(tr.has_gt() ? fmt::format("{}: track '{}' has no external velocities (v_ext, w_ext); expected "
                                              "them, or --ext-from-gt HZ to derive them from its ground truth",
                                              files[k], tr.name())
                                : fmt::format("{}: track '{}' has no external velocities (v_ext, w_ext) and no "
                                              "ground truth (gt_x, gt_y) to derive them from; expected either",
                                              files[k], tr.name()));
    try {
      inputs.push_back(build_calibration_input(tracks[k], o));
    } catch (const std::invalid_argument& e) {
      throw Failure(fmt::format("{}: {}", files[k], e.what()));
    }
    if (apply && !inputs.back().has_gt)
      throw Failure(fmt::format("{}: track '{}' has no ground truth (gt_x, gt_y, gt_theta); --apply scores "
                                "dead reckoning against it",
                                files[k], inputs.back().track_name));
  }
  return inputs;
}

// Several tracks are calibrated as one robot: their nominal parameters must agree.
void check_same_robot(const std::vector<CalibrationInput>& inputs, const std::vector<std::string>& files) {
  const auto differs = [](double a, double b) { return std::abs(a - b) > 1e-9 * std::max(std::abs(a), std::abs(b)); };
  for (std::size_t k = 1; k < inputs.size(); ++k) {
    const OdometryParams &a = inputs[0].nominal, &b = inputs[k].nominal;
    if (differs(a.wheel_radius_left_m, b.wheel_radius_left_m) ||
        differs(a.wheel_radius_right_m, b.wheel_radius_right_m) || differs(a.wheel_base_m, b.wheel_base_m))
      throw Failure(fmt::format(
          "{}: nominal R_L/R_R/D = {}/{}/{} m differ from {}'s {}/{}/{} m; expected tracks of one robot",
          files[k], b.wheel_radius_left_m, b.wheel_radius_right_m, b.wheel_base_m, files[0],
          a.wheel_radius_left_m, a.wheel_radius_right_m, a.wheel_base_m));
  }
}

CalibrationRunInfo make_options(const CalibrateArgs& a, const std::vector<CalibrationInput>& inputs) {
  CalibrationRunInfo info;
  info.track_files = a.tracks;
  info.ext_from_gt_rate_hz = a.ext_from_gt_hz;
  CalibrationOptions& o = info.options;
  if (!parse_calibration_method(a.method, &o.method))
    throw Failure(fmt::format("--method '{}': unknown method, expected adaptive-pf, pf, dkf, batch or none",
                              a.method));
  const bool pf = o.method == CalibrationMethod::pf || o.method == CalibrationMethod::adaptive_pf;
  for (const CLI::Option* opt : {a.resampler_opt, a.policy_opt, a.particles_opt})
    if (given(opt) && !pf)
      throw Failure(fmt::format("{} applies to --method pf and adaptive-pf only (got --method {})",
                                opt->get_name(), a.method));
  const OdometryParams& nom = inputs.front().nominal;
  const double r_nom = 0.5 * (nom.wheel_radius_left_m + nom.wheel_radius_right_m);
  const double r_scale = r_nom / kPaperRadiusM, d_scale = nom.wheel_base_m / kPaperWheelBaseM;

  const CalibrationRanges ranges = default_calibration_ranges(nom);
  Range r_left = ranges.wheel_radius_left_m;
  Range r_right = ranges.wheel_radius_right_m;
  Range base = ranges.wheel_base_m;
  if (!a.init_radius_range.empty()) r_left = r_right = parse_range("--init-radius-range", a.init_radius_range);
  if (!a.init_wheel_base_range.empty()) base = parse_range("--init-wheel-base-range", a.init_wheel_base_range);
  info.init_radius_m = {std::min(r_left.lo, r_right.lo), std::max(r_left.hi, r_right.hi)};
  info.init_wheel_base_m = base;

  o.pf = o.method == CalibrationMethod::adaptive_pf ? filters::PfCalibratorParams::adaptive_defaults()
                                                    : filters::PfCalibratorParams{};
  o.pf.wheel_radius_left_m = r_left;
  o.pf.wheel_radius_right_m = r_right;
  o.pf.wheel_base_m = base;
  o.pf.random_walk_sigma_m *= r_scale;
  o.pf.alpha *= r_scale;
  o.pf.dispersion_per_particle_m *= r_scale;
  o.pf.min_random_walk_sigma_m *= r_scale;
  if (!a.resampler.empty() && !filters::parse_resampler(a.resampler, &o.pf.resampler))
    throw Failure(fmt::format("--resampler '{}': expected multinomial, stratified, systematic or residual",
                              a.resampler));
  if (!a.policy.empty() && !filters::parse_resample_policy(a.policy, &o.pf.policy))
    throw Failure(fmt::format("--policy '{}': expected every, neff or max", a.policy));
  if (a.particles > 0) o.pf.particles = a.particles;
  o.pf.seed = a.seed;
  o.pf.threads = a.threads;

  const auto centre = [](const Range& r) { return 0.5 * (r.lo + r.hi); };
  const auto uniform_sd = [](const Range& r) { return (r.hi - r.lo) / std::sqrt(12.0); };
  o.dkf.initial = {centre(r_left), centre(r_right), centre(base)};
  o.dkf.initial_sd_radius_m = std::max(uniform_sd(r_left), uniform_sd(r_right));
  o.dkf.initial_sd_wheel_base_m = uniform_sd(base);
  o.dkf.radius_walk_m_per_sqrt_s *= r_scale;
  o.dkf.wheel_base_walk_m_per_sqrt_s *= d_scale;

  if (!(std::isfinite(a.tolerance_pct) && a.tolerance_pct > 0.0 && a.tolerance_pct < 100.0))
    throw Failure(fmt::format("--tolerance {}: expected a percentage in (0, 100)", a.tolerance_pct));
  o.convergence_tolerance = a.tolerance_pct / 100.0;
  std::string why;
  if (!o.IsValid(&why)) throw Failure(fmt::format("--method {}: {}", a.method, why));
  return info;
}

// ---------------------------------------------------------------- summary

std::string pct(double estimate, double truth) { return fmt::format("{:+.3f} %", 100.0 * (estimate - truth) / truth); }

std::string param_line(const char* name, double estimate, const std::optional<OdometryParams>& truth,
                       double OdometryParams::*field) {
  if (!truth) return fmt::format("    {:<3} {:.5f} m   (truth unknown)", name, estimate);
  const double t = (*truth).*field;
  return fmt::format("    {:<3} {:.5f} m   true {:.5f} m   error {}", name, estimate, t, pct(estimate, t));
}

std::string rmse_line(const char* what, double calibrated, double nominal, const char* unit) {
  if (!std::isfinite(calibrated)) return fmt::format("    {:<13} unknown (no ground truth)", what);
  std::string s = fmt::format("    {:<13} {:.4f} {}", what, calibrated, unit);
  if (std::isfinite(nominal)) {
    s += fmt::format("   (nominal {:.4f} {}", nominal, unit);
    const double imp = rmse_improvement_pct(nominal, calibrated);
    if (std::isfinite(imp)) s += fmt::format(", {:.1f} % {}", std::abs(imp), imp >= 0.0 ? "better" : "worse");
    s += ")";
  }
  return s;
}

std::vector<std::string> summary_lines(const CalibrationResult& r, const std::vector<CalibrationInput>& inputs,
                                       const std::vector<TrackCalibrationScore>& nominal,
                                       const CalibrationRunInfo& info) {
  std::vector<std::string> out;
  const bool pf = r.method == CalibrationMethod::pf || r.method == CalibrationMethod::adaptive_pf;
  std::string how = fmt::format("initial R {:.4f}–{:.4f} m, D {:.4f}–{:.4f} m", info.init_radius_m.lo,
                                info.init_radius_m.hi, info.init_wheel_base_m.lo, info.init_wheel_base_m.hi);
  if (pf) {
    const filters::PfCalibratorParams p = effective_pf_params(info.options);
    how += fmt::format("; {} resampling, policy {}, {} particles{}, seed {}", filters::to_string(p.resampler),
                       filters::to_string(p.policy), p.particles,
                       r.method == CalibrationMethod::adaptive_pf ? " initially" : "", p.seed);
  }
  out.push_back(fmt::format("{} calibration on {} track{} ({})", to_string(r.method), inputs.size(),
                            inputs.size() == 1 ? "" : "s", how));
  const double tol_pct = 100.0 * info.options.convergence_tolerance;
  for (std::size_t k = 0; k < r.tracks.size() && k < inputs.size(); ++k) {
    const TrackCalibrationScore& s = r.tracks[k];
    out.push_back(fmt::format("  track {} ({}):", s.track, info.track_files[k]));
    out.push_back(param_line("R_R", s.final_params.wheel_radius_right_m, s.truth_final,
                             &OdometryParams::wheel_radius_right_m));
    out.push_back(param_line("R_L", s.final_params.wheel_radius_left_m, s.truth_final,
                             &OdometryParams::wheel_radius_left_m));
    out.push_back(param_line("D", s.final_params.wheel_base_m, s.truth_final, &OdometryParams::wheel_base_m));
    if (!inputs[k].truth)
      out.push_back("    convergence   unknown (the track has no truth: no sim.effects metadata)");
    else if (r.method == CalibrationMethod::batch)
      out.push_back("    convergence   n/a (an offline fit of the whole track)");
    else if (s.convergence_time_s)
      out.push_back(fmt::format("    convergence   {:.2f} s (both radii within {:g} % of the truth from then on)",
                                *s.convergence_time_s, tol_pct));
    else
      out.push_back(fmt::format("    convergence   never (not within {:g} % of the truth to the end)", tol_pct));
    const std::vector<double> changes = inputs[k].truth ? inputs[k].truth->change_times() : std::vector<double>{};
    for (std::size_t c = 0; r.method != CalibrationMethod::batch && c < s.reconvergence_s.size(); ++c) {
      const std::string at = c < changes.size() ? fmt::format(" at {:.2f} s", changes[c]) : "";
      out.push_back(s.reconvergence_s[c]
                        ? fmt::format("    re-convergence after the radius step{}: {:.2f} s", at, *s.reconvergence_s[c])
                        : fmt::format("    re-convergence after the radius step{}: never", at));
    }
    const double np = k < nominal.size() ? nominal[k].pose_rmse_m : NAN;
    const double nh = k < nominal.size() ? nominal[k].heading_rmse_rad : NAN;
    out.push_back(rmse_line("pose RMSE", s.pose_rmse_m, np, "m"));
    out.push_back(rmse_line("heading RMSE", s.heading_rmse_rad, nh, "rad"));
  }
  const OdometryParams& f = r.final_params;
  out.push_back(fmt::format("  final: R_L = {:.5f} m, R_R = {:.5f} m, D = {:.5f} m", f.wheel_radius_left_m,
                            f.wheel_radius_right_m, f.wheel_base_m));
  if (r.method == CalibrationMethod::batch) {
    out.push_back(fmt::format("  cost: {} residual pairs, {:.3g} ms per pair (fit {:.3g} s){}", r.iterations,
                              r.ms_per_iteration, 1e-3 * r.ms_per_iteration * static_cast<double>(r.iterations),
                              r.batch_converged ? "" : "; Ceres did NOT report convergence"));
  } else if (r.method != CalibrationMethod::none) {
    std::string cost =
        fmt::format("  cost: {} iterations, {:.3g} ms per iteration", r.iterations, r.ms_per_iteration);
    if (pf) cost += fmt::format(", mean {:.0f} particles", r.mean_particles);
    out.push_back(cost);
  }
  return out;
}

// ---------------------------------------------------------------- runs

// run_calibration reports no progress: while it runs, one status line on
// stderr when that is a terminal (the Progress rule: not in logs or CI),
// cleared when done or failed.
class StatusLine {
 public:
  explicit StatusLine(const std::string& text) : enabled_(Progress("", "").enabled()) {
    if (!enabled_) return;
    std::fputs(text.c_str(), stderr);
    std::fflush(stderr);
  }
  ~StatusLine() {
    if (enabled_) std::fputs("\r\x1b[2K", stderr), std::fflush(stderr);
  }
  StatusLine(const StatusLine&) = delete;
  StatusLine& operator=(const StatusLine&) = delete;

 private:
  bool enabled_;
};

std::string joined_names(const std::vector<CalibrationInput>& inputs) {
  std::string s;
  for (const auto& in : inputs) s += (s.empty() ? "" : ", ") + in.track_name;
  return s;
}

void run_calibrate(const CalibrateArgs& a) {
  for (const auto& [flag, path] : {std::pair{"--json", &a.json}, std::pair{"--csv", &a.csv},
                                   std::pair{"--figure", &a.figure}, std::pair{"--config-out", &a.config_out}})
    check_output_dir(flag, *path);
  std::vector<CalibrationInput> inputs = build_inputs(a.tracks, a.ext_from_gt_hz, false, a.ext_sigma_v, a.ext_sigma_w);
  check_same_robot(inputs, a.tracks);
  const CalibrationRunInfo info = make_options(a, inputs);
  apply_threads(a.threads);
  std::vector<const CalibrationInput*> ptrs;
  std::size_t samples = 0;
  for (const auto& in : inputs) ptrs.push_back(&in), samples += in.samples.size();

  CalibrationResult result;
  {
    const StatusLine status(fmt::format("calibrating with {} over {} samples…", a.method, samples));
    try {
      result = run_calibration(ptrs, info.options);
    } catch (const std::invalid_argument& e) {
      throw Failure(fmt::format("calibrate: {}", e.what()));
    }
  }

  std::vector<TrackCalibrationScore> nominal;
  for (const auto& in : inputs) nominal.push_back(score_fixed_params(in, in.nominal));
  const std::vector<std::string> lines = summary_lines(result, inputs, nominal, info);
  const std::string json_text = calibration_json(result, ptrs, nominal, info).dump(2) + "\n";
  CalibrationTraceTable table;
  try {
    table = build_trace_table(result, ptrs);
  } catch (const std::invalid_argument& e) {
    throw Failure(fmt::format("calibrate: {}", e.what()));
  }

  // Outputs: the figure first (gnuplot is the likeliest to fail), the JSON last.
  if (!a.figure.empty()) {
    try {
      results::calibration_estimates_figure(
          a.figure, calibration_figure_data(table, fmt::format("{}: {} calibration", joined_names(inputs), a.method)));
    } catch (const std::exception& e) {
      throw Failure(fmt::format("--figure {}: {}", a.figure, e.what()));
    }
  }
  if (!a.csv.empty()) write_file_atomically(a.csv, trace_csv(table));
  if (!a.config_out.empty()) {
    CalibrationFile file;
    file.params = result.final_params;
    std::string files;
    for (const auto& t : a.tracks) files += (files.empty() ? "" : ", ") + t;
    const bool pf = result.method == CalibrationMethod::pf || result.method == CalibrationMethod::adaptive_pf;
    file.comment = fmt::format("calibrated by odotune calibrate: method {}{}\ntracks: {}", a.method,
                               pf ? fmt::format(", seed {}", a.seed) : "", files);
    write_calibration_file(file, a.config_out);
  }
  if (!a.json.empty()) write_file_atomically(a.json, json_text);
  for (const std::string& l : lines) fmt::print("{}\n", l);
  if (!a.figure.empty()) fmt::print("figure: {}.png, {}.svg\n", a.figure, a.figure);
  if (!a.csv.empty()) fmt::print("csv: {}\n", a.csv);
  if (!a.config_out.empty()) fmt::print("calibration: {} (check it on held-out runs: odotune calibrate --apply {} --track …)\n",
                                        a.config_out, a.config_out);
  if (!a.json.empty()) fmt::print("json: {}\n", a.json);
}

void run_apply(const CalibrateArgs& a) {
  for (const CLI::Option* opt : {a.method_opt, a.resampler_opt, a.policy_opt, a.particles_opt, a.seed_opt,
                                 a.radius_opt, a.base_opt, a.tolerance_opt})
    if (given(opt)) throw Failure(fmt::format("{} does not combine with --apply (which replays a calibration file)",
                                              opt->get_name()));
  for (const auto& [flag, path] : {std::pair{"--csv", &a.csv}, std::pair{"--figure", &a.figure},
                                   std::pair{"--config-out", &a.config_out}})
    if (!path->empty()) throw Failure(fmt::format("{} does not combine with --apply (which replays a calibration file)", flag));
  check_output_dir("--json", a.json);
  const CalibrationFile cal = read_calibration_file(a.apply);
  const std::vector<CalibrationInput> inputs = build_inputs(a.tracks, a.ext_from_gt_hz, true, a.ext_sigma_v, a.ext_sigma_w);
  std::vector<AppliedTrack> applied;
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    AppliedTrack t;
    t.file = a.tracks[k];
    t.nominal_params = inputs[k].nominal;
    t.nominal = score_fixed_params(inputs[k], inputs[k].nominal);
    t.calibrated = score_fixed_params(inputs[k], cal.params);
    applied.push_back(std::move(t));
  }
  const std::string json_text = apply_json(a.apply, cal.params, applied).dump(2) + "\n";
  if (!a.json.empty()) write_file_atomically(a.json, json_text);
  const OdometryParams& p = cal.params;
  fmt::print("applied {} (R_L = {:.5f} m, R_R = {:.5f} m, D = {:.5f} m) to {} track{}, against the nominal parameters:\n",
             a.apply, p.wheel_radius_left_m, p.wheel_radius_right_m, p.wheel_base_m, applied.size(),
             applied.size() == 1 ? "" : "s");
  for (const AppliedTrack& t : applied) {
    fmt::print("  track {} ({}):\n", t.calibrated.track, t.file);
    fmt::print("{}\n", rmse_line("pose RMSE", t.calibrated.pose_rmse_m, t.nominal.pose_rmse_m, "m"));
    fmt::print("{}\n", rmse_line("heading RMSE", t.calibrated.heading_rmse_rad, t.nominal.heading_rmse_rad, "rad"));
  }
  if (!a.json.empty()) fmt::print("json: {}\n", a.json);
}

}  // namespace

void register_calibrate(CLI::App& app) {
  auto args = std::make_shared<CalibrateArgs>();
  auto* sub = app.add_subcommand(
      "calibrate", "Calibrate the odometry (wheel radii, wheel base) online from external velocities");
  sub->footer(
      "Examples:\n"
      "  odotune calibrate --track run_cw.csv --track run_ccw.csv --method adaptive-pf --seed 1 \\\n"
      "      --json cal.json --csv cal.csv --figure cal --config-out cal.yaml\n"
      "  odotune calibrate --apply cal.yaml --track held_out.csv --json held_out.json\n"
      "  odotune calibrate --track optiodom.csv --ext-from-gt 10 --method dkf\n"
      "Methods (Fariña, Toledo & Acosta, RA-L 2026): adaptive-pf and pf (particle filters), dkf (dual\n"
      "Kalman filter), batch (offline least squares), none (the nominal parameters). Several tracks are\n"
      "calibrated one after another with the same filter (as UMBmark combines a clockwise and a\n"
      "counter-clockwise run). The truth, the convergence time and the % errors are known for simulated\n"
      "tracks (their sim.effects metadata); pose and heading RMSE need ground truth. Initial ranges\n"
      "default to the nominal radii ±5 % and wheel base ±15 % (the paper's wheelchair ranges);\n"
      "the DKF starts at the range centre with sd = width/√12.");
  sub->add_option("--track", args->tracks, "track file (repeat for several, calibrated in order)")->required();
  args->method_opt =
      sub->add_option("--method", args->method, "adaptive-pf | pf | dkf | batch | none (default adaptive-pf)");
  args->resampler_opt = sub->add_option("--resampler", args->resampler,
                                        "PF resampling: multinomial | stratified | systematic | residual "
                                        "(default systematic)");
  args->policy_opt =
      sub->add_option("--policy", args->policy, "PF resampling policy: every | neff | max (default neff)");
  args->seed_opt = sub->add_option("--seed", args->seed, "PF random seed (same seed ⇒ same estimates)");
  args->particles_opt = sub->add_option("--particles", args->particles,
                                        "PF particles (adaptive-pf: the initial count; default 5000, adaptive 8000)")
                            ->check(CLI::PositiveNumber);
  add_threads_option(sub, &args->threads);
  sub->add_option("--ext-from-gt", args->ext_from_gt_hz,
                  "derive the external velocities from the ground truth at this rate [Hz] (for tracks "
                  "without v_ext/w_ext, e.g. OptiOdom)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--ext-sigma-v", args->ext_sigma_v,
                  "σ of the external speed [m/s] where the track gives no v_ext_var (and for --ext-from-gt); "
                  "default 0.02")
      ->check(CLI::PositiveNumber);
  sub->add_option("--ext-sigma-w", args->ext_sigma_w,
                  "σ of the external yaw rate [rad/s] where the track gives no w_ext_var (and for "
                  "--ext-from-gt); default 0.02")
      ->check(CLI::PositiveNumber);
  args->radius_opt = sub->add_option("--init-radius-range", args->init_radius_range,
                                     "LO,HI: initial range of both radii [m] (default nominal ±5 %)");
  args->base_opt = sub->add_option("--init-wheel-base-range", args->init_wheel_base_range,
                                   "LO,HI: initial range of the wheel base [m] (default nominal ±15 %)");
  args->tolerance_opt = sub->add_option("--tolerance", args->tolerance_pct,
                                        "convergence: within this % of the truth from then on (default 0.5)");
  sub->add_option("--json", args->json, "write the result as JSON to this file");
  sub->add_option("--csv", args->csv, "write the estimates over time as CSV to this file");
  sub->add_option("--figure", args->figure, "write the estimates over time as STEM.png and STEM.svg");
  sub->add_option("--config-out", args->config_out,
                  "write the calibrated parameters (YAML, odotune-calibration/1) for --apply");
  sub->add_option("--apply", args->apply,
                  "replay the tracks with this calibration file and with their nominal parameters, and "
                  "compare pose and heading RMSE (no calibration is run)");
  sub->callback([args] {
    if (args->apply.empty())
      run_calibrate(*args);
    else
      run_apply(*args);
  });
}

}  // namespace odotune::cli
