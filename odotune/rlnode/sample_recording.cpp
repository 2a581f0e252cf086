#include <odotune/rlnode/sample_recording.h>

#include <algorithm>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/rlnode/input_loader.h>

namespace odotune::rlnode {

namespace {

namespace rl = filters::rl;

bool any_of(const UpdateMask& c, int from, int to) {
  return std::any_of(c.begin() + from, c.begin() + to, [](bool b) { return b; });
}

[[noreturn]] void refuse(const RlParams& p, const std::string& what, const SensorParams& sp,
                         const std::string& why) {
  throw std::invalid_argument(fmt::format("{}: {}:{}: {} {}", what, p.file.string(), sp.yaml_line, sp.name,
                                          why));
}

void take(int& role, int s, const RlParams& p, const std::string& what, const char* kind) {
  if (role >= 0) {
    refuse(p, what, p.sensors[s],
           fmt::format("fuses {} as {} does; a recording without a bag has one such stream", kind,
                       p.sensors[role].name));
  }
  role = s;
}

}  // namespace

SampleRoles sample_roles(const RlParams& p, const std::string& what) {
  SampleRoles r;
  for (int s = 0; s < static_cast<int>(p.sensors.size()); ++s) {
    const SensorParams& sp = p.sensors[s];
    const bool position = any_of(sp.config, rl::kX, rl::kRoll),
               orientation = any_of(sp.config, rl::kRoll, rl::kVx);
    const bool linear = any_of(sp.config, rl::kVx, rl::kVroll),
               angular = any_of(sp.config, rl::kVroll, rl::kAx);
    const bool accel = any_of(sp.config, rl::kAx, rl::kStateSize);
    if (sp.differential || sp.relative)
      refuse(p, what, sp, "is differential or relative; expected absolute position fixes or velocities");
    if (sp.kind == SensorKind::imu) {
      if (orientation || accel || linear)
        refuse(p, what, sp,
               "fuses an orientation or accelerations; expected only angular velocities (the gyro)");
      if (angular) take(r.gyro, s, p, what, "a yaw rate");
    } else if (position && (orientation || linear || angular || accel)) {
      refuse(p, what, sp, "fuses a position together with other members; expected x, y only (the fixes)");
    } else if (position) {
      if (sp.kind == SensorKind::twist) refuse(p, what, sp, "is a twist input fusing a position");
      take(r.fixes, s, p, what, "a position");
    } else if (orientation || accel) {
      refuse(p, what, sp, "fuses an orientation or accelerations; expected velocities (the odometry)");
    } else if (linear || angular) {
      if (sp.kind == SensorKind::pose) refuse(p, what, sp, "is a pose input fusing velocities");
      take(r.odometry, s, p, what, "velocities");
    }
  }
  if (r.odometry < 0) {
    throw std::invalid_argument(
        fmt::format("{}: {}: no odomN or twistN fuses velocities; expected the odometry "
                    "as one (e.g. odom0_config with vx and vyaw)",
                    what, p.file.string()));
  }
  return r;
}

namespace {

std::array<double, 36> diagonal6(double a, double b, double c, double d, double e, double f) {
  std::array<double, 36> m{};
  const double v[6] = {a, b, c, d, e, f};
  for (std::size_t i = 0; i < 6; ++i) m[i * 7] = v[i];
  return m;
}

// The messages in stamp order, each handed to the loader as the node's
// callback would take it (stamp and receive time equal: no transport delay).
void feed(detail::Loader& loader, const RlParams& p, const SampleStreams& st, const SampleRoles& r,
          std::int64_t start_ns) {
  const std::string base = p.base_link_frame;
  std::size_t i = 0, j = 0, k = 0;
  const auto stamp = [](const auto& v, std::size_t n) {
    return n < v.size() ? v[n].stamp_ns : std::numeric_limits<std::int64_t>::max();
  };
  while (i < st.odometry.size() || j < st.gyro.size() || k < st.fixes.size()) {
    const std::int64_t a = stamp(st.odometry, i), b = stamp(st.gyro, j), c = stamp(st.fixes, k);
    const std::int64_t t = std::min({a, b, c});
    if (t == c) {
      const FixSample& f = st.fixes[k++];
      if (t < start_ns || r.fixes < 0) continue;
      GpsFix g;
      g.stamp_ns = g.receive_ns = t;
      g.p = {f.x, f.y, 0.0};
      g.cov = Eigen::Vector3d(f.var_x, f.var_y, std::max(f.var_x, f.var_y)).asDiagonal();
      loader.on_local_fix(g);
    } else if (t == a) {
      const TwistSample& s = st.odometry[i++];
      if (t < start_ns) continue;
      const auto cov = diagonal6(st.odometry_var_vx, st.odometry_var_vx, st.odometry_var_vx, 1e6, 1e6,
                                 st.odometry_var_vyaw);
      if (p.sensors[r.odometry].kind == SensorKind::twist) {
        bags::ros::TwistWithCovarianceStamped m;
        m.header.stamp_ns = t;
        m.header.frame_id = base;
        m.linear.x = s.vx;
        m.angular.z = s.vyaw;
        m.covariance = cov;
        loader.on_twist(m, r.odometry, t);
      } else {
        bags::ros::Odometry m;
        m.header.stamp_ns = t;
        m.header.frame_id = p.odom_frame;
        m.child_frame_id = base;
        m.orientation.w = 1.0;
        m.linear.x = s.vx;
        m.angular.z = s.vyaw;
        m.twist_covariance = cov;
        loader.on_odometry(m, r.odometry, t);
      }
    } else {
      const RateSample& s = st.gyro[j++];
      if (t < start_ns || r.gyro < 0) continue;
      bags::ros::Imu m;
      m.header.stamp_ns = t;
      m.header.frame_id = base;
      m.orientation.w = 1.0;
      m.orientation_covariance[0] = -1.0;
      m.linear_acceleration_covariance[0] = -1.0;
      m.angular_velocity.z = s.vyaw;
      m.angular_velocity_covariance = {st.gyro_var, 0, 0, 0, st.gyro_var, 0, 0, 0, st.gyro_var};
      loader.on_imu(m, r.gyro, t);
    }
  }
}

}  // namespace

Recording load_sample_recording(const RlParams& params, const SampleStreams& st, std::int64_t start_ns) {
  const SampleRoles r = sample_roles(params, st.name);
  const auto missing = [&](int s, const char* what) {
    throw std::invalid_argument(fmt::format("{}: {}:{}: {} fuses {}, which {} does not have", st.name,
                                            params.file.string(), params.sensors[s].yaml_line,
                                            params.sensors[s].name, what, st.name));
  };
  if (r.gyro >= 0 && st.gyro.empty()) missing(r.gyro, "a yaw rate (the gyro, gyro_z)");
  if (r.fixes >= 0 && st.fixes.empty())
    missing(r.fixes, "position fixes (aps_x, aps_y; odotune fixes makes them)");
  if (st.odometry.empty()) missing(r.odometry, "the odometry");
  if (params.navsat.present) {
    throw std::invalid_argument(
        fmt::format("{}: {}: navsat_transform_node's section: a recording without a bag "
                    "has its fixes in the world frame already; expected no navsat section",
                    st.name, params.file.string()));
  }
  Recording rec;
  rec.params = params;
  rec.notes = params.notes;
  rec.bag = st.name;
  rec.gps_sensor = r.fixes;
  rec.gps_transform.fixed = true;  // identity: the fixes are in the world frame
  const RecordingOptions options;
  detail::Loader loader(params, options, rec);
  feed(loader, params, st, r, start_ns);
  loader.finish();
  if (rec.inputs.empty()) {
    throw std::invalid_argument(fmt::format("{}: no sample at or after {:.3f} s", st.name,
                                            static_cast<double>(start_ns) * 1e-9));
  }
  rec.origin_ns = 0;
  rec.start_ns = rec.inputs.front().receive_ns;
  rec.end_ns = rec.inputs.back().receive_ns;
  return rec;
}

}  // namespace odotune::rlnode
