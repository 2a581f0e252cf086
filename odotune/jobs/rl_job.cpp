#include <odotune/jobs/rl_job.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <odotune/core/atomic_file.h>
#include <odotune/core/failure.h>
#include <odotune/core/output_paths.h>
#include <odotune/rlnode/prepared_recording.h>

namespace odotune::jobs {
namespace {

namespace rl = filters::rl;

constexpr std::int64_t kEnd = std::numeric_limits<std::int64_t>::max();

std::int64_t at_seconds(const rlnode::Recording& rec, const std::optional<double>& s) {
  return s ? rl_time_ns(rec, *s) : kEnd;
}

nlohmann::json json_of(const objectives::FixScore& s) {
  return {{"rmse_m", s.rmse_m}, {"fixes", s.fixes}, {"finite", s.finite}};
}

nlohmann::json json_of(const RlProtocolScores& p) {
  return {{"outage", json_of(p.outage)}, {"every_fifth_fix", json_of(p.every_fifth)}};
}

}  // namespace

void write_rl_trajectory(const std::filesystem::path& path, const std::vector<rlnode::TrajectoryPoint>& points,
                         const std::string& comment) {
  std::ostringstream out;
  out << "# " << comment << "\n";
  for (const rlnode::TrajectoryPoint& p : points) {
    const Eigen::Quaterniond q(rlnode::rotation_rpy(p.state[rl::kRoll], p.state[rl::kPitch],
                                                    p.state[rl::kYaw]));
    out << fmt::format("{:.9f} {:.6f} {:.6f} {:.6f} {:.9f} {:.9f} {:.9f} {:.9f}\n",
                       static_cast<double>(p.time_ns) * 1e-9, p.state[rl::kX], p.state[rl::kY], p.state[rl::kZ],
                       q.x(), q.y(), q.z(), q.w());
  }
  core::write_atomically(path, "trajectory", out.str());
}

rlnode::RlParams read_rl_file(const RlSource& src) {
  try {
    return rlnode::read_rl_params(src.params_file, src.node_name, src.filter, src.navsat_params);
  } catch (const std::exception& e) {
    // A navsat_transform_node file alone: its keys, if that is what it is.
    try {
      if (src.node_name.empty() && src.navsat_params.empty())
        return rlnode::read_navsat_params(src.params_file);
    } catch (const std::exception&) {  // not a navsat file either: the first reason stands
    }
    throw core::Failure(e.what());
  }
}

rlnode::Matrix15 rl_noise_from(const std::filesystem::path& file, const std::string& node_name) {
  try {
    return rlnode::read_rl_params(file, node_name).process_noise_covariance;
  } catch (const std::exception& e) {
    throw core::Failure(e.what());
  }
}

std::int64_t rl_time_ns(const rlnode::Recording& rec, double seconds) {
  return rec.origin_ns + static_cast<std::int64_t>(std::llround(seconds * 1e9));
}

double rl_seconds(const rlnode::Recording& rec, std::int64_t time_ns) {
  return static_cast<double>(time_ns - rec.origin_ns) * 1e-9;
}

std::pair<std::string, rlnode::Pose3> parse_tf(const std::string& text) {
  const auto eq = text.find('=');
  std::vector<double> v;
  if (eq != std::string::npos && eq > 0) {
    std::stringstream ss(text.substr(eq + 1));
    std::string item;
    while (std::getline(ss, item, ',')) {
      try {
        std::size_t used = 0;
        v.push_back(std::stod(item, &used));
        if (used != item.size()) v.clear();
      } catch (const std::exception&) {
        v.clear();
        break;
      }
    }
  }
  if (eq == std::string::npos || eq == 0 || v.size() != 6) {
    throw core::Failure(
        fmt::format("--tf {}: expected FRAME=x,y,z,roll,pitch,yaw (the frame's pose in base_link, "
                    "metres and radians)",
                    text));
  }
  rlnode::Pose3 p;
  p.t = {v[0], v[1], v[2]};
  p.R = rlnode::rotation_rpy(v[3], v[4], v[5]);
  return {text.substr(0, eq), p};
}

std::string rmse_text(int decimals, double v_m) {
  return std::isfinite(v_m) ? fmt::format("{:.{}f} m", v_m, decimals) : "diverged";
}

// "FROM=TO" (ROS's FROM:=TO remapping, as for rosrun or a launch file's <remap>).
std::pair<std::string, std::string> parse_remap(const std::string& text) {
  const std::size_t eq = text.find('=');
  const std::string from = text.substr(0, eq), to = eq == std::string::npos ? "" : text.substr(eq + 1);
  if (eq == std::string::npos || from.empty() || to.empty() || to.find('=') != std::string::npos)
    throw core::Failure(fmt::format(
        "--remap {}: expected FROM=TO, e.g. --remap odometry/wheel=/husky_velocity_controller/odom", text));
  return {from, to};
}

RlSource rl_source_of(const formats::ExperimentRl& x, const std::filesystem::path& bag,
                      std::optional<filters::rl::RlFilterType> filter) {
  RlSource src;
  src.filter = filter;
  src.params_file = x.params;
  src.bag = bag;
  src.node_name = x.node_name;
  src.tf = x.tf;
  src.gps_topic = x.gps_topic;
  src.navsat_params = x.navsat_params;
  src.remap = x.remap;
  src.gps_heading_fit_s = x.gps_heading_fit_s;
  return src;
}

namespace {

// The bag's options from the flags (--tf, --gps-topic, --remap); throws
// Failure naming a flag.
rlnode::RecordingOptions recording_options(const RlSource& src) {
  rlnode::RecordingOptions options;
  for (const std::string& t : src.tf) options.frames.insert(parse_tf(t));
  options.gps_topic = src.gps_topic;
  options.from_s = src.from_s;
  for (const std::string& r : src.remap) options.remap.insert(parse_remap(r));
  return options;
}

}  // namespace

RlLoaded load_rl(const RlSource& src) {
  if (src.bag.empty())
    throw core::Failure(
        "--rl-params: expected the robot's recording, --bag BAG, or the project's tracks, --track T");
  const rlnode::RecordingOptions options = recording_options(src);
  try {
    const rlnode::RlParams params = rlnode::read_rl_params(src.params_file, src.node_name, src.filter,
                                                           src.navsat_params);
    rlnode::PreparedRecording p = rlnode::prepare_recording(src.bag, params, options, src.gps_heading_fit_s);
    return {std::move(p.rec), std::move(p.alignment)};
  } catch (const core::Failure&) {
    throw;
  } catch (const std::exception& e) {
    throw core::Failure(e.what());
  }
}

namespace {

// The eval's replays and scores: the span and the protocols of the request.
objectives::RlBagEvalOptions bag_eval_options(const rlnode::Recording& rec, const RlEvalRequest& request) {
  objectives::RlBagEvalOptions o;
  o.until_ns = at_seconds(rec, request.until_s);
  if (request.from_s) o.from_ns = at_seconds(rec, request.from_s);
  o.outage_s = request.outages_s;
  o.outage_every_s = request.outage_every_s;
  o.keep_trajectory = !request.trajectory_out.empty();
  return o;
}

RlEvalOutcome eval_outcome(const RlLoaded& loaded, const objectives::RlBagScores& scores,
                           std::int64_t until_ns) {
  const rlnode::Recording& rec = loaded.rec;
  RlEvalOutcome out;
  out.bag = rec.bag;
  out.params_file = rec.params.file;
  out.filter = rec.params.filter;
  out.final_state = scores.run.final_state;
  out.processed = scores.run.processed;
  out.rejected = scores.run.rejected;
  out.alignment = loaded.alignment;
  out.notes = rec.notes;
  out.duration_s = rl_seconds(rec, std::min(rec.end_ns, until_ns));
  out.heldout = scores.heldout;
  out.protocols = scores.protocols;
  out.outages = scores.outages;
  out.outage_windows = scores.outage_windows;
  return out;
}

void write_rl_fixes(const std::filesystem::path& path, const std::vector<objectives::RlPlacedFix>& fixes) {
  std::ostringstream text;
  text << "# GPS fixes in the odom frame as navsat_transform_node placed them: t [s] x [m] y [m]\n";
  for (const objectives::RlPlacedFix& f : fixes)
    text << fmt::format("{:.9f} {:.4f} {:.4f}\n", static_cast<double>(f.stamp_ns) * 1e-9, f.odom.x(),
                        f.odom.y());
  core::write_atomically(path, "fixes", text.str());
}

void write_rl_eval_json(const std::filesystem::path& path, const RlEvalRequest& request,
                        const RlEvalOutcome& out) {
  nlohmann::json j = {
      {"bag", out.bag.string()},
      {"params", out.params_file.string()},
      {"noise_from", request.noise_from.string()},
      {"duration_s", out.duration_s},
      {"final_position_m", {out.final_state[rl::kX], out.final_state[rl::kY], out.final_state[rl::kZ]}},
      {"final_yaw_rad", out.final_state[rl::kYaw]},
      {"processed", out.processed},
      {"rejected", out.rejected}};
  if (out.heldout) j["heldout_fixes"] = json_of(*out.heldout);
  if (out.protocols) j["after_from"] = json_of(*out.protocols);
  if (out.outages) {
    j["simulated_outages"] = json_of(*out.outages);
    j["simulated_outages"]["lengths_s"] = request.outages_s;
    j["simulated_outages"]["every_s"] = request.outage_every_s;
    j["simulated_outages"]["windows"] = out.outage_windows;
  }
  core::write_atomically(path, "JSON", j.dump(2) + "\n");
}

}  // namespace

RlEvalOutcome run_rl_eval(const RlEvalRequest& request) {
  if (!request.trajectory_out.empty())
    core::check_output_file("--trajectory-out", request.trajectory_out.string());
  if (!request.json_out.empty()) core::check_output_file("--json", request.json_out.string());
  if (!request.fixes_out.empty()) core::check_output_file("--fixes-out", request.fixes_out.string());
  const RlLoaded loaded = load_rl(request.src);
  const rlnode::Recording& rec = loaded.rec;
  rlnode::ReplaySettings s = rlnode::settings_of(rec.params);
  if (!request.noise_from.empty()) s.process_noise = rl_noise_from(request.noise_from, rec.params.node_name);
  const objectives::RlBagEvalOptions options = bag_eval_options(rec, request);
  const objectives::RlBagScores scores = objectives::score_rl_bag(rec, s, options);
  RlEvalOutcome out = eval_outcome(loaded, scores, options.until_ns);
  if (!request.trajectory_out.empty()) {
    // With the protocols, the outage protocol's run: GPS fused until from_s only.
    const std::string what = scores.protocols ? fmt::format("GPS fused until {} s only", *request.from_s)
                                              : std::string("all inputs");
    write_rl_trajectory(request.trajectory_out,
                        scores.protocols ? scores.outage_trajectory : scores.run.trajectory,
                        fmt::format("robot_localization {}_node replayed by odotune: {} with {}, {}",
                                    filters::rl::to_string(rec.params.filter), rec.bag.filename().string(),
                                    rec.params.file.filename().string(), what));
  }
  if (!request.fixes_out.empty()) write_rl_fixes(request.fixes_out, scores.fixes);
  if (!request.json_out.empty()) write_rl_eval_json(request.json_out, request, out);
  return out;
}

}  // namespace odotune::jobs
