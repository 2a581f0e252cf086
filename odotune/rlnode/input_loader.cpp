#include <odotune/rlnode/input_loader.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/rlnode/geodesy.h>

namespace odotune::rlnode::detail {

const Pose3* Loader::find_frame(const std::string& frame) const {
  static const Pose3 kIdentity;
  if (frame.empty() || frame == p_.base_link_frame) return &kIdentity;
  if (auto it = o_.frames.find(frame); it != o_.frames.end()) return &it->second;
  if (auto it = tf_.find(frame); it != tf_.end()) return &it->second;
  return nullptr;
}

Pose3 Loader::frame_in_base(const std::string& frame, int s) const {
  if (const Pose3* p = find_frame(frame)) return *p;
  throw std::invalid_argument(
      fmt::format("{}: {} ({}) is in frame '{}', and neither the bag's /tf_static nor --tf gives {} -> {}; "
                  "expected --tf {}=x,y,z,roll,pitch,yaw (the frame's pose in {})",
                  rec_.bag.string(), sensor(s).name, sensor(s).topic, frame, p_.base_link_frame, frame, frame,
                  p_.base_link_frame));
}

// RosFilter keeps, per callback, the last stamp it took and drops a message
// stamped before it.
bool Loader::in_order(const std::string& callback, std::int64_t stamp_ns) {
  auto [it, fresh] = last_stamp_.try_emplace(callback, stamp_ns);
  if (!fresh && stamp_ns < it->second) {
    ++out_of_order_;
    return false;
  }
  it->second = stamp_ns;
  return true;
}

void Loader::store(const Prepared& m, InputKind kind, int s, std::int64_t stamp_ns, std::int64_t receive_ns,
                   double threshold, const Eigen::Vector3d& lever, bool gravity_from_state, int fix) {
  Input in;
  in.stamp_ns = stamp_ns;
  in.receive_ns = receive_ns;
  in.kind = kind;
  in.sensor = static_cast<std::uint8_t>(s);
  in.threshold = threshold;
  in.lever = lever;
  in.gravity_from_state = gravity_from_state;
  in.fix = fix;
  in.slot = static_cast<std::uint32_t>(rec_.pool.size());
  for (int i = 0; i < rl::kStateSize; ++i) {
    if (m.mask[i]) in.idx[in.n++] = static_cast<std::uint8_t>(i);
  }
  for (int i = 0; i < in.n; ++i) rec_.pool.push_back(m.z[in.idx[i]]);
  for (int i = 0; i < in.n; ++i) {
    for (int j = 0; j < in.n; ++j) rec_.pool.push_back(m.R(in.idx[i], in.idx[j]));
  }
  rec_.inputs.push_back(in);
}

// odometryCallback: the pose part (odomN_config's pose members) and the twist
// part (its velocities, in the message's child frame).
void Loader::on_odometry(const ros::Odometry& m, int s, std::int64_t receive_ns) {
  const SensorParams& sp = sensor(s);
  rl::Mask pose_mask = sp.config, twist_mask = sp.config;
  std::fill(pose_mask.begin() + rl::kVx, pose_mask.begin() + rl::kAx, false);
  std::fill(twist_mask.begin(), twist_mask.begin() + rl::kVx, false);
  const bool any_pose = std::any_of(pose_mask.begin(), pose_mask.end(), [](bool b) { return b; });
  const bool any_twist = std::any_of(twist_mask.begin(), twist_mask.end(), [](bool b) { return b; });
  if (any_pose) {
    PoseInput in{m.header.stamp_ns, receive_ns, m.header.frame_id, {}, to_mat6(m.pose_covariance), false, ""};
    in.pose.t = {m.position.x, m.position.y, m.position.z};
    in.pose.R = rotation_of_quaternion(m.orientation.x, m.orientation.y, m.orientation.z, m.orientation.w);
    if (sp.pose_use_child_frame && m.child_frame_id != p_.base_link_frame) in.source = m.child_frame_id;
    const std::string callback = sp.name + "_pose";
    if (in_order(callback, in.stamp_ns)) prepare_pose(in, s, pose_mask, callback);
  }
  if (any_twist) {
    TwistInput in{m.header.stamp_ns,
                  receive_ns,
                  m.child_frame_id,
                  {m.linear.x, m.linear.y, m.linear.z},
                  {m.angular.x, m.angular.y, m.angular.z},
                  to_mat6(m.twist_covariance)};
    if (in_order(sp.name + "_twist", in.stamp_ns)) {
      prepare_twist(in, s, twist_mask, sp.twist_rejection_threshold, InputKind::twist);
    }
  }
}

void Loader::on_pose(const ros::PoseStamped& m, int s, std::int64_t receive_ns) {
  const SensorParams& sp = sensor(s);
  rl::Mask mask = sp.config;
  std::fill(mask.begin() + rl::kVx, mask.end(), false);
  PoseInput in{m.header.stamp_ns, receive_ns, m.header.frame_id, {}, Mat6::Zero(), false, ""};
  if (m.covariance) in.cov = to_mat6(*m.covariance);
  in.pose.t = {m.position.x, m.position.y, m.position.z};
  in.pose.R = rotation_of_quaternion(m.orientation.x, m.orientation.y, m.orientation.z, m.orientation.w);
  if (in_order(sp.name, in.stamp_ns)) prepare_pose(in, s, mask, sp.name);
}

// twistCallback: twistN_config's velocity (and, as the node keeps them,
// acceleration) members, in the message's frame.
void Loader::on_twist(const ros::TwistWithCovarianceStamped& m, int s, std::int64_t receive_ns) {
  const SensorParams& sp = sensor(s);
  rl::Mask mask = sp.config;
  std::fill(mask.begin(), mask.begin() + rl::kVx, false);
  TwistInput in{m.header.stamp_ns,
                receive_ns,
                m.header.frame_id,
                {m.linear.x, m.linear.y, m.linear.z},
                {m.angular.x, m.angular.y, m.angular.z},
                to_mat6(m.covariance)};
  if (in_order(sp.name, in.stamp_ns))
    prepare_twist(in, s, mask, sp.twist_rejection_threshold, InputKind::twist);
}

// preparePose. Poses are taken in the world frame; an IMU's orientation is
// reported in the world but measured by a sensor mounted in its frame, so its
// roll, pitch and yaw lose the mounting's angles and are turned by its yaw.
void Loader::prepare_pose(const PoseInput& in, int s, rl::Mask mask, const std::string& callback) {
  const SensorParams& sp = sensor(s);
  Pose3 target;  // the message's frame in the target frame
  if (in.imu) {
    target = frame_in_base(in.frame, s);
  } else if (!sp.differential && !in.frame.empty() && in.frame != p_.world_frame) {
    throw std::invalid_argument(
        fmt::format("{}: {} ({}) poses are in frame '{}', expected the world frame '{}'", rec_.bag.string(),
                    sp.name, sp.topic, in.frame, p_.world_frame));
  }
  const Rpy offset = rpy_of(target.R);
  const Eigen::Matrix3d mask_rotation = in.imu ? yaw_rotation(offset.yaw) : target.R;
  rotate_mask(mask, rl::kX, mask_rotation);
  rotate_mask(mask, rl::kRoll, mask_rotation);
  // The source frame's base_link pose, T_source←base, and the covariance
  // turned by its rotation (post-multiplied: Rᵀ·Σ·R per block).
  Pose3 source_to_base;
  Mat6 cov = in.cov;
  if (!in.source.empty()) {
    const Pose3 b = frame_in_base(in.source, s);
    source_to_base = {-(b.R.transpose() * b.t), b.R.transpose()};
    const Mat6 src6 = block_rotation(source_to_base.R);
    cov = src6.transpose() * in.cov * src6;
  }
  const Mat6 rot6 = block_rotation(mask_rotation);
  const Mat6 cov_rotated = rot6 * cov * rot6.transpose();

  Pose3 pose = in.pose;
  if (in.imu) {
    pose.R = imu_orientation_in_base(in.pose.R, target);
    target = {};
  }
  if (sp.differential) {  // the node turns the covariance only, not the pose
    prepare_differential(in, pose, cov_rotated, cov, rot6, s, mask, callback);
    return;
  }
  pose = {pose.R * source_to_base.t + pose.t, pose.R * source_to_base.R};
  if (sp.relative) {
    const Pose3& first = initial_.try_emplace(callback, pose).first->second;
    pose = {first.R.transpose() * (pose.t - first.t), first.R.transpose() * pose.R};
  }
  pose = {target.R * pose.t + target.t, target.R * pose.R};
  Prepared m;
  m.mask = mask;
  m.z.segment<3>(rl::kX) = pose.t;
  const Rpy a = rpy_of(pose.R);
  m.z[rl::kRoll] = a.roll;
  m.z[rl::kPitch] = a.pitch;
  m.z[rl::kYaw] = a.yaw;
  m.R.topLeftCorner<6, 6>() = cov_rotated;
  if (p_.two_d_mode) force_two_d(m);
  store(m, in.imu ? InputKind::imu_orientation : InputKind::pose, s, in.stamp_ns, in.receive_ns,
        sp.pose_rejection_threshold);
}

// A differential pose input: the motion since its previous message, as a
// body-frame twist over the time between their stamps, with covariance
// (Σ_now + Σ_prev)·Δt (preparePose's differential branch).
void Loader::prepare_differential(const PoseInput& in, const Pose3& pose, const Mat6& cov_rotated,
                                  const Mat6& cov, const Mat6& rot6, int s, const rl::Mask& mask,
                                  const std::string& callback) {
  auto prev = previous_.find(callback);
  if (prev != previous_.end()) {
    const double dt = static_cast<double>(in.stamp_ns - prev->second.stamp_ns) * 1e-9;
    if (!(dt > 0.0)) {
      // robot_localization would divide by zero here and fuse nothing finite.
      ++repeated_differential_;
      return;
    }
    const Pose3& a = prev->second.pose;
    const Eigen::Vector3d dp = a.R.transpose() * (pose.t - a.t);
    const Rpy dr = rpy_of(a.R.transpose() * pose.R);
    TwistInput tw{in.stamp_ns,
                  in.receive_ns,
                  p_.base_link_frame,
                  dp / dt,
                  Eigen::Vector3d(dr.roll, dr.pitch, dr.yaw) / dt,
                  Mat6::Zero()};
    tw.cov = (cov_rotated + rot6 * prev->second.cov * rot6.transpose()) * dt;
    rl::Mask twist_mask{};
    for (int i = 0; i < 6; ++i) twist_mask[rl::kVx + i] = mask[i];
    prepare_twist(tw, s, twist_mask, sensor(s).pose_rejection_threshold,
                  in.imu ? InputKind::imu_orientation : InputKind::pose);
  }
  previous_[callback] = {pose, cov, in.stamp_ns};
}

// prepareTwist: velocities rotated from the message's frame into base_link;
// the ω × r term of a sensor away from base_link is added by the replay.
void Loader::prepare_twist(const TwistInput& in, int s, rl::Mask mask, double threshold, InputKind kind) {
  const Pose3 f = frame_in_base(in.frame, s);
  rotate_mask(mask, rl::kVx, f.R);
  rotate_mask(mask, rl::kVroll, f.R);
  const Mat6 rot6 = block_rotation(f.R);
  Prepared m;
  m.mask = mask;
  m.z.segment<3>(rl::kVx) = f.R * in.lin;
  m.z.segment<3>(rl::kVroll) = f.R * in.ang;
  m.R.block<6, 6>(rl::kVx, rl::kVx) = rot6 * in.cov * rot6.transpose();
  if (p_.two_d_mode) force_two_d(m);
  store(m, kind, s, in.stamp_ns, in.receive_ns, threshold, f.t);
}

// imuCallback: orientation (unless its covariance starts with −1), angular
// velocity and linear acceleration, each as its own measurement.
void Loader::on_imu(const ros::Imu& m, int s, std::int64_t receive_ns) {
  const SensorParams& sp = sensor(s);
  const auto& c = sp.config;
  const bool orientation = c[rl::kRoll] || c[rl::kPitch] || c[rl::kYaw];
  const bool rates = c[rl::kVroll] || c[rl::kVpitch] || c[rl::kVyaw];
  const bool accel = c[rl::kAx] || c[rl::kAy] || c[rl::kAz];
  if (orientation && std::abs(m.orientation_covariance[0] + 1.0) >= 1e-9) {
    PoseInput in{m.header.stamp_ns, receive_ns, m.header.frame_id, {}, Mat6::Zero(), true, ""};
    in.pose.R = rotation_of_quaternion(m.orientation.x, m.orientation.y, m.orientation.z, m.orientation.w);
    in.cov.bottomRightCorner<3, 3>() = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(
        m.orientation_covariance.data());
    rl::Mask mask{};
    for (int i = rl::kRoll; i <= rl::kYaw; ++i) mask[i] = c[i];
    const std::string callback = sp.name + "_pose";
    if (in_order(callback, in.stamp_ns)) prepare_pose(in, s, mask, callback);
  }
  if (rates && std::abs(m.angular_velocity_covariance[0] + 1.0) >= 1e-9) {
    TwistInput in{m.header.stamp_ns,
                  receive_ns,
                  m.header.frame_id,
                  Eigen::Vector3d::Zero(),
                  {m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z},
                  Mat6::Zero()};
    in.cov.bottomRightCorner<3, 3>() = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(
        m.angular_velocity_covariance.data());
    rl::Mask mask{};
    for (int i = rl::kVroll; i <= rl::kVyaw; ++i) mask[i] = c[i];
    if (in_order(sp.name + "_twist", in.stamp_ns)) {
      prepare_twist(in, s, mask, sp.twist_rejection_threshold, InputKind::twist);
    }
  }
  if (accel && std::abs(m.linear_acceleration_covariance[0] + 1.0) >= 1e-9 &&
      in_order(sp.name + "_acceleration", m.header.stamp_ns)) {
    prepare_acceleration(m, s, receive_ns);
  }
}

// prepareAcceleration as robot_localization's ROS 1 release has it: gravity
// (when asked) removed in the IMU's frame using its orientation, then the
// vector rotated into base_link; the lever-arm terms, and gravity when the
// IMU gives no orientation, are the replay's.
void Loader::prepare_acceleration(const ros::Imu& m, int s, std::int64_t receive_ns) {
  const SensorParams& sp = sensor(s);
  const Pose3 f = frame_in_base(m.header.frame_id, s);
  Eigen::Vector3d acc(m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z);
  const bool has_orientation = std::abs(m.orientation_covariance[0] + 1.0) >= 1e-9;
  const bool gravity = sp.remove_gravitational_acceleration;
  if (gravity && has_orientation) {
    const Eigen::Matrix3d att = rotation_of_quaternion(m.orientation.x, m.orientation.y, m.orientation.z,
                                                       m.orientation.w);
    const Eigen::Vector3d g(0.0, 0.0, p_.gravitational_acceleration);
    acc -= sp.relative ? Eigen::Vector3d(f.R.transpose() * att.transpose() * g)
                       : Eigen::Vector3d(att.transpose() * g);
  }
  rl::Mask mask{};
  for (int i = rl::kAx; i <= rl::kAz; ++i) mask[i] = sp.config[i];
  rotate_mask(mask, rl::kAx, f.R);
  const Eigen::Matrix3d cov = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(
      m.linear_acceleration_covariance.data());
  Prepared out;
  out.mask = mask;
  out.z.segment<3>(rl::kAx) = f.R * acc;
  out.R.block<3, 3>(rl::kAx, rl::kAx) = f.R * cov * f.R.transpose();
  if (p_.two_d_mode) force_two_d(out);
  store(out, InputKind::acceleration, s, m.header.stamp_ns, receive_ns, sp.accel_rejection_threshold, f.t,
        gravity && !has_orientation);
}

// The IMU heading navsat_transform_node would take at its datum: the
// orientation corrected for the mounting as the filter corrects it, plus
// declination and yaw_offset (the grid's convergence is added per fix).
void Loader::note_imu_orientation(const ros::Imu& m, std::int64_t receive_ns) {
  if (std::abs(m.orientation_covariance[0] + 1.0) < 1e-9) return;
  const Pose3* mount = find_frame(m.header.frame_id);
  if (!mount) return;
  const Eigen::Matrix3d R = imu_orientation_in_base(
      rotation_of_quaternion(m.orientation.x, m.orientation.y, m.orientation.z, m.orientation.w), *mount);
  const double yaw = rpy_of(R).yaw + p_.navsat.magnetic_declination_radians + p_.navsat.yaw_offset;
  rec_.navsat_headings.emplace_back(receive_ns, yaw);
}

// navsat_transform_node's input: good fixes projected on the UTM grid (or a
// local tangent plane with use_local_cartesian), with their covariance.
void Loader::on_fix(const ros::NavSatFix& m, std::int64_t receive_ns) {
  if (m.status < 0 || !std::isfinite(m.latitude_deg) || !std::isfinite(m.longitude_deg) ||
      !std::isfinite(m.altitude_m)) {
    ++no_fix_;
    return;
  }
  GpsFix f;
  f.stamp_ns = m.header.stamp_ns;
  f.receive_ns = receive_ns;
  if (p_.navsat.use_local_cartesian) {
    if (!local_) local_ = std::make_unique<GeographicLib::LocalCartesian>(m.latitude_deg, m.longitude_deg, 0.0);
    local_->Forward(m.latitude_deg, m.longitude_deg, m.altitude_m, f.p.x(), f.p.y(), f.p.z());
  } else {
    // The datum's zone for every fix (the first fix's without a datum).
    const UtmPoint g = utm_forward(m.latitude_deg, m.longitude_deg, utm_zone_);
    utm_zone_ = g.zone;
    f.p = {g.easting_m, g.northing_m, m.altitude_m};
    f.convergence_rad = g.convergence_rad;
  }
  if (p_.navsat.zero_altitude) f.p.z() = 0.0;
  f.cov = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(m.position_covariance.data());
  add_fix(f, m.header.frame_id);
}

void Loader::on_local_fix(const GpsFix& fix) { add_fix(fix, ""); }

// navsat's datum (datumCallback): its grid point, in its own zone, which every
// fix then takes; the local plane's origin with use_local_cartesian.
GpsTransform Loader::set_datum(const std::array<double, 3>& datum) {
  const NavsatParams& nv = p_.navsat;
  GpsTransform t;
  t.fixed = true;
  double convergence = 0.0;
  if (nv.use_local_cartesian) {
    local_ = std::make_unique<GeographicLib::LocalCartesian>(datum[0], datum[1], 0.0);
  } else {
    const UtmPoint g = utm_forward(datum[0], datum[1]);
    utm_zone_ = g.zone;
    t.grid_origin = {g.easting_m, g.northing_m, 0.0};
    convergence = g.convergence_rad;
  }
  // The datum's heading as the node's IMU heading there, the odom frame's
  // origin and zero yaw at the datum.
  t.rotation_rad = -(datum[2] + nv.magnetic_declination_radians + nv.yaw_offset + convergence);
  return t;
}

void Loader::add_fix(const GpsFix& f, const std::string& frame_id) {
  const std::int64_t receive_ns = f.receive_ns;
  if (!in_order(sensor(rec_.gps_sensor).name + "_pose", f.stamp_ns)) return;
  rec_.fixes.push_back(f);
  const SensorParams& sp = sensor(rec_.gps_sensor);
  Prepared out;  // the position is filled in by the replay, from the fix and the datum
  for (int i = rl::kX; i <= rl::kZ; ++i) out.mask[i] = sp.config[i];
  if (p_.two_d_mode) force_two_d(out);
  // The antenna's offset from base_link, when its frame is known (navsat uses
  // the identity when it cannot look the transform up).
  const Pose3* antenna_frame = find_frame(frame_id);
  const Eigen::Vector3d antenna = antenna_frame ? antenna_frame->t : Eigen::Vector3d::Zero();
  store(out, InputKind::gps, rec_.gps_sensor, f.stamp_ns, receive_ns, sp.pose_rejection_threshold, antenna,
        false, static_cast<int>(rec_.fixes.size()) - 1);
}

// controlCallback: a command in base_link (or without a frame) becomes the
// node's latest control, at its header's stamp (TwistStamped) or at the time
// the node receives it (Twist, stamped with now()); another frame is ignored.
void Loader::on_command(const ros::TwistStamped& m, std::int64_t receive_ns) {
  if (p_.control.stamped && !m.header.frame_id.empty() && m.header.frame_id != p_.base_link_frame) {
    ++foreign_commands_;
    return;
  }
  Input in;
  in.stamp_ns = p_.control.stamped ? m.header.stamp_ns : receive_ns;
  in.receive_ns = receive_ns;
  in.kind = InputKind::command;
  in.n = filters::rl::kControlSize;
  in.slot = static_cast<std::uint32_t>(rec_.pool.size());
  for (double v : {m.linear.x, m.linear.y, m.linear.z, m.angular.x, m.angular.y, m.angular.z})
    rec_.pool.push_back(v);
  rec_.inputs.push_back(in);
  ++commands_;
}

void Loader::finish() {
  if (p_.control.enabled) {
    rec_.notes.push_back(fmt::format("use_control: {} commands read{}", commands_,
                                     foreign_commands_ > 0
                                         ? fmt::format("; {} in a frame other than {} ignored, as the node "
                                                       "ignores them",
                                                       foreign_commands_, p_.base_link_frame)
                                         : ""));
  }
  if (out_of_order_ > 0) {
    rec_.notes.push_back(
        fmt::format("{} messages stamped before their topic's previous one were dropped, as the "
                    "node drops them",
                    out_of_order_));
  }
  if (no_fix_ > 0)
    rec_.notes.push_back(fmt::format("{} NavSatFix messages without a fix were skipped", no_fix_));
}

}  // namespace odotune::rlnode::detail
