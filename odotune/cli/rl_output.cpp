#include <odotune/cli/rl_output.h>

#include <odotune/cli/choices.h>

#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace odotune::cli {
namespace {

namespace rl = filters::rl;

std::string metres(const objectives::FixScore& s) {
  return s.finite ? fmt::format("{:.3f} m ({} fixes)", s.rmse_m, s.fixes) : "diverged";
}

// The outages' score, or "n/a" when no outage window fits the recording
// (an empty score is not a divergence).
std::string outage_metres(const objectives::FixScore& s, std::size_t windows) {
  return windows > 0 ? metres(s) : "n/a";
}

// A table cell: "0.245 m", or "diverged".
std::string column(const objectives::FixScore& s) {
  return s.finite ? fmt::format("{:.3f} m", s.rmse_m) : "diverged";
}

std::string change(const objectives::FixScore& a, const objectives::FixScore& b) {
  if (!a.finite || !b.finite || !(a.rmse_m > 0.0)) return fmt::format("{} -> {}", metres(a), metres(b));
  return fmt::format("{:.3f} -> {:.3f} m  ({:+.1f} %, {} fixes)", a.rmse_m, b.rmse_m,
                     100.0 * (b.rmse_m / a.rmse_m - 1.0), b.fixes);
}

void print_notes(const std::vector<std::string>& notes, const std::optional<rlnode::GpsAlignment>& a) {
  for (const std::string& n : notes) fmt::print("  note: {}\n", n);
  if (a) {
    fmt::print("  GPS heading fitted on the first {} fixes: navsat's rotation {:.4f} rad (residual {:.2f} m; "
               "yaw_offset {:.4f} rad with this IMU)\n",
               a->fixes, a->transform.rotation_rad, a->rms_m, a->yaw_offset_rad);
  }
}

}  // namespace

void print_rl_keys(const rlnode::RlParams& p) {
  if (p.sensors.empty() && p.navsat.present) {
    fmt::print(
        "{}: navsat_transform_node's parameters alone ({}), {} keys; give them with --navsat-params beside "
        "the filter's file\n",
        p.file.filename().string(), p.navsat.node_name, p.keys.size());
  } else {
    fmt::print("{}: robot_localization {} ({}, section {}), {} keys\n", p.file.filename().string(),
               filters::rl::display_name(p.filter), p.ros2 ? "ROS 2" : "ROS 1",
               p.node_name.empty() ? "(top level)" : p.node_name, p.keys.size());
  }
  for (const rlnode::KeyReport& k : p.keys)
    fmt::print("  {:>4}  {:<13} {:<36} {}\n", k.line, rlnode::to_string(k.use), k.key, k.section);
  for (const std::string& n : p.notes) fmt::print("  note: {}\n", n);
}

std::vector<const CLI::Option*> given_options(const CLI::App& app) {
  return app.get_options([](const CLI::Option* o) { return o->count() > 0; });
}

void add_rl_source_options(CLI::App* sub, jobs::RlSource& src) {
  sub->add_option(
         "--rl-params", src.params_file,
         "robot_localization parameter file (ROS 1 or ROS 2 YAML): replay its ekf_node or ukf_node on --bag")
      ->check(CLI::ExistingFile)
      ->group(kRlGroup);
  sub->add_option("--bag", src.bag, "--rl-params: the robot's bag (ROS 1 .bag, MCAP, rosbag2 .db3 or folder)")
      ->group(kRlBagGroup);
  sub->add_option("--node", src.node_name, "--rl-params: the filter's section of the file when it has several")
      ->group(kRlGroup);
  add_enum_option(sub, "--filter", src.filter, filters::rl::kAllRlFilterTypes,
                  "--rl-params: ekf_node or ukf_node, for a file that does not say (a section named *ukf*, or "
                  "ukf_node's alpha, kappa or beta, is the UKF's)")
      ->group(kRlGroup);
  sub->add_option("--tf", src.tf,
                  "--rl-params: FRAME=x,y,z,roll,pitch,yaw, a sensor frame's pose in base_link (repeat; "
                  "else /tf_static in the bag)")
      ->group(kRlBagGroup);
  sub->add_option("--gps-topic", src.gps_topic, "--rl-params: the NavSatFix topic behind navsat's output")
      ->group(kRlBagGroup);
  sub->add_option("--navsat-params", src.navsat_params,
                  "--rl-params: navsat_transform_node's parameters from a file of their own")
      ->check(CLI::ExistingFile)
      ->group(kRlBagGroup);
  sub->add_option("--remap", src.remap,
                  "--rl-params: FROM=TO, the node's topic FROM read from the bag's TO, as ROS's FROM:=TO "
                  "(repeat; an input's topic or use_control's cmd_vel)")
      ->group(kRlBagGroup);
  sub->add_option("--gps-heading-fit", src.gps_heading_fit_s,
                  "--rl-params: fit navsat's GPS-to-odom rotation on the first SECONDS of fixes (for an IMU "
                  "whose absolute yaw cannot be trusted) instead of taking the IMU's heading")
      ->check(CLI::PositiveNumber)
      ->group(kRlBagGroup);
}

void add_rl_track_options(CLI::App* sub, jobs::RlTrackSource& src) {
  objectives::RlTrackOptions& o = src.options;
  sub->add_option("--calibration", src.calibration,
                  "--rl-params with --track: apply this odometry calibration (calibrate --config-out) to every "
                  "track first: wheel radii and base as the track's geometry, or a twist's scales and delay")
      ->check(CLI::ExistingFile)
      ->group(kRlTrackGroup);
  add_enum_option(sub, "--odometry", o.odometry, tracks::kAllOdometryInputs,
                  "--rl-params with --track: the track's odometry input (default: its wheels, else its "
                  "v_cmd/w_cmd as its source.body_velocity says)")
      ->group(kRlTrackGroup);
  sub->add_option("--fix-sigma-m", o.fix_sigma_m,
                  "--rl-params with --track: σ [m] of fixes whose track gives no aps_var_x/aps_var_y")
      ->check(CLI::PositiveNumber)
      ->group(kRlTrackGroup);
  sub->add_option_function<std::vector<double>>(
         "--twist-variance",
         [&o](const std::vector<double>& v) {
           if (v.size() != 2)
             throw CLI::ValidationError("--twist-variance", "expected VX,VYAW (two variances)");
           o.odometry_var_vx = v[0];
           o.odometry_var_vyaw = v[1];
         },
         "--rl-params with --track: the odometry twist's covariance diagonal, vx and vyaw [(m/s)², (rad/s)²], "
         "as the drive controller publishes it (default 0.001,0.03: Clearpath's diff_drive_controller "
         "twist_covariance_diagonal)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber)
      ->group(kRlTrackGroup);
  sub->add_option("--gyro-variance", o.gyro_var,
                  "--rl-params with --track: the gyro's yaw-rate variance [(rad/s)²] (default (0.02 °/s)², the "
                  "phidgets_spatial driver's)")
      ->check(CLI::PositiveNumber)
      ->group(kRlTrackGroup);
}

namespace {

std::string truth_text(const objectives::TruthScore& s) {
  if (s.samples == 0) return "n/a";
  return s.finite ? fmt::format("{:.3f} m", s.rmse_m) : "diverged";
}

std::string truth_change(const objectives::TruthScore& a, const objectives::TruthScore& b) {
  const std::string pct = a.samples > 0 && b.samples > 0 && a.rmse_m > 0.0
                              ? fmt::format(" ({:+.1f} %)", 100.0 * (b.rmse_m / a.rmse_m - 1.0))
                              : "";
  return fmt::format("{} -> {}{}", truth_text(a), truth_text(b), pct);
}

}  // namespace

void print_rl_track_eval(const jobs::RlTrackEvalOutcome& o) {
  for (const jobs::RlTrackRow& r : o.rows) {
    const objectives::RlTrackScores& s = r.scores;
    fmt::print("{}: robot_localization {} ({}) over {:.1f} s, odometry {}: {} measurements, {} rejected\n",
               r.track.filename().string(), filters::rl::display_name(o.filter),
               o.params_file.filename().string(), r.duration_s, tracks::to_string(r.odometry), s.processed,
               s.rejected);
    fmt::print("  {}{}\n", r.start_note,
               std::isfinite(r.initial_heading_error_rad)
                   ? fmt::format(" (against gt_theta: {:+.3f} rad)", r.initial_heading_error_rad)
                   : "");
    fmt::print("  against ground truth: every fix fused RMSE {}; through {} simulated fix outages RMSE {}\n",
               truth_text(s.run), s.windows, truth_text(s.outages));
    fmt::print("  against the fixes: held-out fixes (5 folds of 1 s blocks) RMSE {}; outages RMSE {}\n",
               metres(s.heldout_fixes), outage_metres(s.outage_fixes, s.windows));
  }
  if (o.rows.size() > 1) {
    std::size_t windows = 0;
    for (const auto& r : o.rows) windows += r.scores.windows;
    fmt::print("all {} tracks: ground truth, fixes fused {}, outages {}; held-out fixes {}, outages {}\n",
               o.rows.size(), truth_text(o.run), truth_text(o.outages), metres(o.heldout_fixes),
               outage_metres(o.outage_fixes, windows));
  }
}

void print_rl_track_tune(const jobs::RlTuneRequest& r, const jobs::RlTrackTuneOutcome& o) {
  print_rl_tune(r, o.tune);
  fmt::print(
      "  against ground truth on the tuned tracks (not used by the tune), the file's values -> tuned:\n");
  for (std::size_t k = 0; k < o.before.size(); ++k) {
    fmt::print("    {}: fixes fused {}; outages {}\n", o.before[k].track.filename().string(),
               truth_change(o.before[k].scores.run, o.after[k].scores.run),
               truth_change(o.before[k].scores.outages, o.after[k].scores.outages));
  }
}

void print_rl_eval(const jobs::RlEvalOutcome& o) {
  const rl::State& x = o.final_state;
  fmt::print("{}: robot_localization {} ({}) over {:.1f} s: {} measurements, {} rejected\n",
             o.bag.filename().string(), filters::rl::display_name(o.filter), o.params_file.filename().string(),
             o.duration_s, o.processed, o.rejected);
  fmt::print("  final pose: x {:.4f} m, y {:.4f} m, z {:.4f} m, yaw {:.4f} rad\n", x[rl::kX], x[rl::kY],
             x[rl::kZ], x[rl::kYaw]);
  if (o.heldout) fmt::print("  held-out fixes (5 folds of 1 s blocks): RMSE {}\n", metres(*o.heldout));
  if (o.protocols) {
    fmt::print("  after --from: GPS outage RMSE {}; every 5th fix held out: RMSE {}\n",
               metres(o.protocols->outage), metres(o.protocols->every_fifth));
  }
  if (o.outages) {
    fmt::print("  simulated GPS outages ({} windows): RMSE {}\n", o.outage_windows,
               outage_metres(*o.outages, o.outage_windows));
  }
  print_notes(o.notes, o.alignment);
}

void print_rl_tune(const jobs::RlTuneRequest& r, const jobs::RlTuneOutcome& o) {
  fmt::print("{}: robot_localization {} ({}), tuned on {:.1f}-{:.1f} s of {:.1f} s; fitness {}, {} process "
             "noise{}; outages of {} s ({} windows)\n",
             o.bag.filename().string(), filters::rl::display_name(o.filter), o.params_file.filename().string(),
             o.span_from_s, o.span_until_s, o.duration_s, objectives::to_string(r.options.fitness),
             objectives::to_string(r.options.space),
             r.options.input_covariances ? " and input covariances" : "", fmt::join(r.options.outage_s, ", "),
             o.outage_windows);
  fmt::print(
      "  grid of block factors: {} combinations, then the profile: tuning fitness {:.4f} (the file's values "
      "{:.4f})\n",
      o.grid.points, o.grid.fitness, o.baseline_fitness);
  if (o.starts.size() > 1 && !(r.search.refine_decades > 0.0))
    fmt::print("  no seeded stage (--refine 0): every seed gives the same file\n");
  if (o.starts.size() > 1 || o.judged) {
    fmt::print("  {:>6} {:>10} {:>14} {:>14}{}\n", "seed", "tuning", "held-out fixes", "outages",
               o.judged ? fmt::format(" {:>16} {:>16}", "judged: outage", "every 5th") : "");
    for (std::size_t k = 0; k < o.starts.size(); ++k) {
      const jobs::RlStartOutcome& st = o.starts[k];
      fmt::print("  {:>6} {:>10.4f} {:>14} {:>14}{}{}\n", st.seed, st.fitness, column(st.heldout),
                 column(st.outage),
                 st.judged
                     ? fmt::format(" {:>16} {:>16}", column(st.judged->outage), column(st.judged->every_fifth))
                     : "",
                 k == o.written ? "   <- written" : "");
    }
  }
  fmt::print("  tuning span, held-out fixes:  {}\n", change(o.baseline_heldout, o.tuned_heldout));
  fmt::print("  tuning span, outages:  {}\n", change(o.baseline_outage, o.tuned_outage));
  if (o.baseline_judged && o.tuned_judged) {
    fmt::print("  judged on {:.1f}-{:.1f} s, never seen by the tune:\n", o.judged_from_s, o.judged_until_s);
    fmt::print("    GPS outage:            {}\n", change(o.baseline_judged->outage, o.tuned_judged->outage));
    fmt::print("    every 5th fix held out: {}\n",
               change(o.baseline_judged->every_fifth, o.tuned_judged->every_fifth));
  }
  const jobs::RlStartOutcome& w = o.starts[o.written];
  std::string determined, not_determined;
  for (std::size_t i = 0; i < o.param_names.size(); ++i) {
    const bool yes = w.profiles.empty() || w.profiles[i].determined;
    std::string& list = yes ? determined : not_determined;
    list += fmt::format("{}{} ×{:.3g}", list.empty() ? "" : ", ", o.param_names[i], o.factors[i]);
    if (!w.profiles.empty()) list += fmt::format(" [{:.2g}, {:.2g}]", w.profiles[i].lo, w.profiles[i].hi);
  }
  fmt::print("  factors (range within {:g} % of the best tuning fitness):\n    {}\n",
             100.0 * r.search.tolerance, determined.empty() ? "none" : determined);
  if (!not_determined.empty())
    fmt::print("  not determined by this recording (kept at the file's values):\n    {}\n", not_determined);
  fmt::print("  {} evaluations in {:.1f} s\n", o.summary.evaluations, o.summary.seconds);
  print_notes(o.notes, o.alignment);
  if (!r.config_out.empty())
    fmt::print("  wrote {} ({})\n", r.config_out.string(), r.ros1_out ? "ROS 1" : "ROS 2");
}

}  // namespace odotune::cli
