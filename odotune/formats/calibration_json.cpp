#include <odotune/formats/calibration_json.h>

#include <cmath>
#include <optional>

namespace odotune::formats {

namespace {

using nlohmann::json;

json number_or_null(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
json number_or_null(const std::optional<double>& v) { return v ? number_or_null(*v) : json(nullptr); }

json params_json(const filters::OdometryParams& p) {
  return {{"wheel_radius_left_m", number_or_null(p.wheel_radius_left_m)},
          {"wheel_radius_right_m", number_or_null(p.wheel_radius_right_m)},
          {"wheel_base_m", number_or_null(p.wheel_base_m)}};
}

double pct_error(double estimate, double truth) { return 100.0 * (estimate - truth) / truth; }

json error_pct_json(const filters::OdometryParams& est, const std::optional<filters::OdometryParams>& truth) {
  if (!truth) return nullptr;
  return {
      {"wheel_radius_left_m", number_or_null(pct_error(est.wheel_radius_left_m, truth->wheel_radius_left_m))},
      {"wheel_radius_right_m",
       number_or_null(pct_error(est.wheel_radius_right_m, truth->wheel_radius_right_m))},
      {"wheel_base_m", number_or_null(pct_error(est.wheel_base_m, truth->wheel_base_m))}};
}

json range_json(const filters::PfCalibratorParams::Range& r) { return json::array({r.lo, r.hi}); }

// Mean of the finite values; NaN when there is none.
double finite_mean(const std::vector<double>& v) {
  double sum = 0.0;
  int n = 0;
  for (double x : v)
    if (std::isfinite(x)) sum += x, ++n;
  return n > 0 ? sum / n : NAN;
}

json options_json(const CalibrationRunInfo& info, calibration::CalibrationMethod method) {
  json o;
  o["init_radius_range_m"] = range_json(info.init_radius_m);
  o["init_wheel_base_range_m"] = range_json(info.init_wheel_base_m);
  o["ext_from_gt_hz"] = info.ext_from_gt_rate_hz > 0 ? json(info.ext_from_gt_rate_hz) : json(nullptr);
  o["convergence_tolerance"] = info.options.convergence_tolerance;
  if (method == calibration::CalibrationMethod::pf || method == calibration::CalibrationMethod::adaptive_pf) {
    const filters::PfCalibratorParams pf = calibration::effective_pf_params(info.options);
    o["resampler"] = std::string(filters::to_string(pf.resampler));
    o["policy"] = std::string(filters::to_string(pf.policy));
    o["seed"] = pf.seed;
    o["particles"] = pf.particles;
    o["random_walk_sigma_m"] = pf.random_walk_sigma_m;
    if (method == calibration::CalibrationMethod::adaptive_pf) {
      o["alpha_m_per_m_s"] = pf.alpha;
      o["dispersion_per_particle_m"] = pf.dispersion_per_particle_m;
      o["particles_range"] = json::array({pf.min_particles, pf.max_particles});
    }
  }
  if (method == calibration::CalibrationMethod::batch_pose) {
    const calibration::PoseCalibrationOptions& p = info.options.pose;
    o["segment_s"] = p.segment_s > 0.0 ? json(p.segment_s) : json(nullptr);  // null: whole runs
    o["fit_start_heading"] = p.fit_start_heading;
    o["loss_scale_m"] = p.loss_scale_m;
  }
  if (method == calibration::CalibrationMethod::dkf) {
    const filters::DualKfParams& k = info.options.dkf;
    o["initial"] = params_json(k.initial);
    o["initial_sd_radius_m"] = k.initial_sd_radius_m;
    o["initial_sd_wheel_base_m"] = k.initial_sd_wheel_base_m;
    o["radius_walk_m_per_sqrt_s"] = k.radius_walk_m_per_sqrt_s;
    o["wheel_base_walk_m_per_sqrt_s"] = k.wheel_base_walk_m_per_sqrt_s;
  }
  return o;
}

}  // namespace

double rmse_improvement_pct(double a, double b) {
  if (!std::isfinite(a) || !std::isfinite(b) || a <= 0.0) return NAN;
  return 100.0 * (a - b) / a;
}

json calibration_json(const calibration::CalibrationResult& result,
                      const std::vector<const calibration::CalibrationInput*>& inputs,
                      const std::vector<calibration::TrackCalibrationScore>& nominal,
                      const CalibrationRunInfo& info) {
  json j;
  j["format"] = "odotune-calibration-result/1";
  j["mode"] = "calibrate";
  j["method"] = std::string(calibration::to_string(result.method));
  j["final"] = params_json(result.final_params);
  if (!result.trace.estimate.empty()) {
    const filters::CalibEstimate& e = result.trace.estimate.back();
    j["final_sd"] = {{"wheel_radius_left_m", e.sd_radius_left_m},
                     {"wheel_radius_right_m", e.sd_radius_right_m},
                     {"wheel_base_m", e.sd_wheel_base_m}};
  } else {
    j["final_sd"] = nullptr;
  }
  const std::optional<filters::OdometryParams> last_truth = result.tracks.empty()
                                                                ? std::nullopt
                                                                : result.tracks.back().truth_final;
  j["truth"] = last_truth ? params_json(*last_truth) : json(nullptr);
  j["error_pct"] = error_pct_json(result.final_params, last_truth);
  j["convergence_time_s"] = result.tracks.empty() ? json(nullptr)
                                                  : number_or_null(result.tracks.front().convergence_time_s);

  std::vector<double> pose, heading, nominal_pose, nominal_heading;
  std::vector<int> iterations(inputs.size(), 0);
  for (int k : result.trace.track)
    if (k >= 0 && static_cast<std::size_t>(k) < iterations.size()) ++iterations[static_cast<std::size_t>(k)];
  json tracks = json::array();
  for (std::size_t k = 0; k < result.tracks.size(); ++k) {
    const calibration::TrackCalibrationScore& s = result.tracks[k];
    json t;
    t["track"] = s.track;
    t["file"] = k < info.track_files.size() ? json(info.track_files[k]) : json(nullptr);
    t["final"] = params_json(s.final_params);
    t["truth"] = s.truth_final ? params_json(*s.truth_final) : json(nullptr);
    t["error_pct"] = error_pct_json(s.final_params, s.truth_final);
    t["convergence_time_s"] = number_or_null(s.convergence_time_s);
    json rec = json::array();
    std::vector<double> changes;
    if (k < inputs.size() && inputs[k]->truth) changes = inputs[k]->truth->change_times();
    for (std::size_t c = 0; c < s.reconvergence_s.size(); ++c)
      rec.push_back({{"change_at_s", c < changes.size() ? json(changes[c]) : json(nullptr)},
                     {"time_s", number_or_null(s.reconvergence_s[c])}});
    t["reconvergence"] = rec;
    t["pose_rmse_m"] = number_or_null(s.pose_rmse_m);
    t["heading_rmse_rad"] = number_or_null(s.heading_rmse_rad);
    t["v_rmse_m_s"] = number_or_null(s.v_rmse_m_s);
    t["w_rmse_rad_s"] = number_or_null(s.w_rmse_rad_s);
    const double np = k < nominal.size() ? nominal[k].pose_rmse_m : NAN;
    const double nh = k < nominal.size() ? nominal[k].heading_rmse_rad : NAN;
    t["nominal"] = {{"pose_rmse_m", number_or_null(np)}, {"heading_rmse_rad", number_or_null(nh)}};
    t["iterations"] = k < iterations.size() ? iterations[k] : 0;
    if (k < inputs.size()) {
      t["ext_noise"] = inputs[k]->ext_noise;
      t["ext_sigma_v_m_s"] = inputs[k]->ext_sigma_v_m_s > 0.0 ? json(inputs[k]->ext_sigma_v_m_s)
                                                              : json(nullptr);
      t["ext_sigma_w_rad_s"] = inputs[k]->ext_sigma_w_rad_s > 0.0 ? json(inputs[k]->ext_sigma_w_rad_s)
                                                                  : json(nullptr);
    }
    tracks.push_back(t);
    pose.push_back(s.pose_rmse_m), heading.push_back(s.heading_rmse_rad);
    nominal_pose.push_back(np), nominal_heading.push_back(nh);
  }
  j["pose_rmse_m"] = number_or_null(finite_mean(pose));
  j["heading_rmse_rad"] = number_or_null(finite_mean(heading));
  j["nominal_pose_rmse_m"] = number_or_null(finite_mean(nominal_pose));
  j["nominal_heading_rmse_rad"] = number_or_null(finite_mean(nominal_heading));
  j["ms_per_iteration"] = number_or_null(result.ms_per_iteration);
  j["iterations"] = result.iterations;
  j["mean_particles"] = number_or_null(result.mean_particles);
  j["memory_restarts"] = result.memory_restarts;
  if (calibration::is_offline(result.method)) {
    j["batch_converged"] = result.batch_converged;
    j["batch_residuals"] = result.batch_residuals;
  }
  j["options"] = options_json(info, result.method);
  j["tracks"] = tracks;
  return j;
}

json apply_json(const std::string& calibration_file, const filters::OdometryParams& params,
                const std::vector<AppliedTrack>& tracks) {
  json j;
  j["format"] = "odotune-calibration-result/1";
  j["mode"] = "apply";
  json cal = params_json(params);
  cal["file"] = calibration_file;
  j["calibration"] = cal;
  json arr = json::array();
  std::vector<double> np, nh, cp, ch;
  for (const AppliedTrack& a : tracks) {
    json t;
    t["track"] = a.calibrated.track;
    t["file"] = a.file;
    t["nominal"] = {{"params", params_json(a.nominal_params)},
                    {"pose_rmse_m", number_or_null(a.nominal.pose_rmse_m)},
                    {"heading_rmse_rad", number_or_null(a.nominal.heading_rmse_rad)}};
    t["calibrated"] = {{"pose_rmse_m", number_or_null(a.calibrated.pose_rmse_m)},
                       {"heading_rmse_rad", number_or_null(a.calibrated.heading_rmse_rad)}};
    t["improvement_pct"] = {
        {"pose", number_or_null(rmse_improvement_pct(a.nominal.pose_rmse_m, a.calibrated.pose_rmse_m))},
        {"heading",
         number_or_null(rmse_improvement_pct(a.nominal.heading_rmse_rad, a.calibrated.heading_rmse_rad))}};
    arr.push_back(t);
    np.push_back(a.nominal.pose_rmse_m), nh.push_back(a.nominal.heading_rmse_rad);
    cp.push_back(a.calibrated.pose_rmse_m), ch.push_back(a.calibrated.heading_rmse_rad);
  }
  j["tracks"] = arr;
  j["mean"] = {{"nominal",
                {{"pose_rmse_m", number_or_null(finite_mean(np))},
                 {"heading_rmse_rad", number_or_null(finite_mean(nh))}}},
               {"calibrated",
                {{"pose_rmse_m", number_or_null(finite_mean(cp))},
                 {"heading_rmse_rad", number_or_null(finite_mean(ch))}}}};
  return j;
}

}  // namespace odotune::formats
