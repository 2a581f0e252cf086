#include <odotune/jobs/calibration_summary.h>

#include <cmath>
#include <optional>

#include <fmt/format.h>

namespace odotune::jobs {

namespace {

using filters::OdometryParams;

std::string percent_of(double estimate, double truth) {
  return fmt::format("{:+.3f} %", 100.0 * (estimate - truth) / truth);
}

std::string param_line(const char* name, double estimate, const std::optional<OdometryParams>& truth,
                       double OdometryParams::*field) {
  if (!truth) return fmt::format("    {:<3} {:.5f} m   (truth unknown)", name, estimate);
  const double t = (*truth).*field;
  return fmt::format("    {:<3} {:.5f} m   true {:.5f} m   error {}", name, estimate, t,
                     percent_of(estimate, t));
}

std::string rmse_line(const char* what, double calibrated, double nominal, const char* unit) {
  if (!std::isfinite(calibrated)) return fmt::format("    {:<13} unknown (no ground truth)", what);
  std::string s = fmt::format("    {:<13} {:.4f} {}", what, calibrated, unit);
  if (std::isfinite(nominal)) {
    s += fmt::format("   (nominal {:.4f} {}", nominal, unit);
    const double imp = formats::rmse_improvement_pct(nominal, calibrated);
    if (std::isfinite(imp)) s += fmt::format(", {:.1f} % {}", std::abs(imp), imp >= 0.0 ? "better" : "worse");
    s += ")";
  }
  return s;
}

// The position fixes online-pose used, and where their variances came from.
std::string fixes_line(const calibration::CalibrationInput& in, const calibration::OnlinePoseOptions& o) {
  std::size_t own = 0;
  for (std::size_t i = 0; i < in.fix_var_x.size(); ++i)
    own += std::isfinite(in.fix_var_x[i]) && std::isfinite(in.fix_var_y[i]) && in.fix_var_x[i] > 0.0 &&
           in.fix_var_y[i] > 0.0;
  std::string var = own == in.fix_t.size() ? "variances from the track (aps_var_x, aps_var_y)"
                                           : fmt::format("σ {:g} m (--fix-sigma-m)", o.fix_sd_m.value_or(0.0));
  if (own > 0 && own < in.fix_t.size())
    var = fmt::format("{} with the track's variances, the others {}", own, var);
  return fmt::format("    fixes         {} position fixes, {}", in.fix_t.size(), var);
}

// What the method started from and how it was set, for the first line.
std::string how_it_ran(const calibration::CalibrationResult& r, const formats::CalibrationRunInfo& info) {
  const bool pf = r.method == calibration::CalibrationMethod::pf ||
                  r.method == calibration::CalibrationMethod::adaptive_pf;
  std::string how = fmt::format("initial R {:.4f}–{:.4f} m, D {:.4f}–{:.4f} m", info.init_radius_m.lo,
                                info.init_radius_m.hi, info.init_wheel_base_m.lo, info.init_wheel_base_m.hi);
  if (r.method == calibration::CalibrationMethod::online_pose) {
    const calibration::OnlinePoseOptions& o = info.options.online_pose;
    const filters::DistanceMemoryParams memory = r.online_pose_memory.value_or(o.filter.memory);
    how = fmt::format(
        "initial R_L {:.5f} m, R_R {:.5f} m, D {:.5f} m, sd {:g} % / {:g} %; start from {}; memory "
        "{:g}–{:g} m rolled",
        o.filter.initial.wheel_radius_left_m, o.filter.initial.wheel_radius_right_m,
        o.filter.initial.wheel_base_m, 100 * o.filter.initial_sd_radius_frac,
        100 * o.filter.initial_sd_wheel_base_frac, calibration::to_string(o.start), memory.min_memory_m,
        memory.max_memory_m);
  }
  if (pf) {
    const filters::PfCalibratorParams p = calibration::effective_pf_params(info.options);
    how += fmt::format("; {} resampling, policy {}, {} particles{}, seed {}", filters::to_string(p.resampler),
                       filters::to_string(p.policy), p.particles,
                       r.method == calibration::CalibrationMethod::adaptive_pf ? " initially" : "", p.seed);
  }
  return how;
}

}  // namespace

std::vector<std::string> calibration_summary_lines(
    const calibration::CalibrationResult& r, const std::vector<calibration::CalibrationInput>& inputs,
    const std::vector<calibration::TrackCalibrationScore>& nominal, const formats::CalibrationRunInfo& info) {
  std::vector<std::string> out;
  const std::string how = how_it_ran(r, info);
  out.push_back(fmt::format("{} calibration on {} track{} ({})", calibration::to_string(r.method),
                            inputs.size(), inputs.size() == 1 ? "" : "s", how));
  const double tol_pct = 100.0 * info.options.convergence_tolerance;
  for (std::size_t k = 0; k < r.tracks.size() && k < inputs.size(); ++k) {
    const calibration::TrackCalibrationScore& s = r.tracks[k];
    out.push_back(fmt::format("  track {} ({}):", s.track, info.track_files[k]));
    if (r.method == calibration::CalibrationMethod::online_pose)
      out.push_back(fixes_line(inputs[k], info.options.online_pose));
    else if (!inputs[k].ext_noise.empty())
      out.push_back("    velocities    " + inputs[k].ext_noise);
    out.push_back(param_line("R_R", s.final_params.wheel_radius_right_m, s.truth_final,
                             &OdometryParams::wheel_radius_right_m));
    out.push_back(param_line("R_L", s.final_params.wheel_radius_left_m, s.truth_final,
                             &OdometryParams::wheel_radius_left_m));
    out.push_back(param_line("D", s.final_params.wheel_base_m, s.truth_final, &OdometryParams::wheel_base_m));
    if (!inputs[k].truth)
      out.emplace_back("    convergence   unknown (the track has no truth: no sim.effects metadata)");
    else if (calibration::is_offline(r.method))
      out.emplace_back("    convergence   n/a (an offline fit of the whole track)");
    else if (s.convergence_time_s)
      out.push_back(
          fmt::format("    convergence   {:.2f} s (both radii within {:g} % of the truth from then on)",
                      *s.convergence_time_s, tol_pct));
    else
      out.push_back(fmt::format("    convergence   never (not within {:g} % of the truth to the end)",
                                tol_pct));
    const std::vector<double> changes = inputs[k].truth ? inputs[k].truth->change_times()
                                                        : std::vector<double>{};
    for (std::size_t c = 0; !calibration::is_offline(r.method) && c < s.reconvergence_s.size(); ++c) {
      const std::string at = c < changes.size() ? fmt::format(" at {:.2f} s", changes[c]) : "";
      out.push_back(s.reconvergence_s[c]
                        ? fmt::format("    re-convergence after the radius step{}: {:.2f} s", at,
                                      *s.reconvergence_s[c])
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
  if (calibration::is_offline(r.method)) {
    out.push_back("  fit: " + r.batch_residuals);
    out.push_back(fmt::format("  cost: {} residual {}, {:.3g} ms each (fit {:.3g} s){}", r.iterations,
                              r.method == calibration::CalibrationMethod::batch_pose ? "positions" : "pairs",
                              r.ms_per_iteration, 1e-3 * r.ms_per_iteration * static_cast<double>(r.iterations),
                              r.batch_converged ? "" : "; Ceres did NOT report convergence"));
  } else if (r.method != calibration::CalibrationMethod::none) {
    std::string cost = fmt::format("  cost: {} iterations, {:.3g} ms per iteration", r.iterations,
                                   r.ms_per_iteration);
    if (r.method == calibration::CalibrationMethod::pf ||
        r.method == calibration::CalibrationMethod::adaptive_pf)
      cost += fmt::format(", mean {:.0f} particles", r.mean_particles);
    if (r.memory_pair)
      cost += fmt::format("; memory restarted {} time(s) (a change found, odotune/filters/memory_pair.h)",
                          r.memory_restarts);
    out.push_back(cost);
  }
  return out;
}

std::vector<std::string> apply_summary_lines(const std::string& calibration_file, const OdometryParams& p,
                                             const std::vector<formats::AppliedTrack>& tracks) {
  std::vector<std::string> out;
  out.push_back(fmt::format(
      "applied {} (R_L = {:.5f} m, R_R = {:.5f} m, D = {:.5f} m) to {} track{}, against the nominal parameters:",
      calibration_file, p.wheel_radius_left_m, p.wheel_radius_right_m, p.wheel_base_m, tracks.size(),
      tracks.size() == 1 ? "" : "s"));
  for (const formats::AppliedTrack& t : tracks) {
    out.push_back(fmt::format("  track {} ({}):", t.calibrated.track, t.file));
    out.push_back(rmse_line("pose RMSE", t.calibrated.pose_rmse_m, t.nominal.pose_rmse_m, "m"));
    out.push_back(rmse_line("heading RMSE", t.calibrated.heading_rmse_rad, t.nominal.heading_rmse_rad, "rad"));
  }
  return out;
}

}  // namespace odotune::jobs
