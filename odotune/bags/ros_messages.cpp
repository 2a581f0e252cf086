#include <odotune/bags/ros_messages.h>

namespace odotune::bags::ros {
namespace {

Header header(WireReader& r) {
  Header h;
  if (r.encoding() == WireEncoding::ros1) r.u32("header.seq");
  h.stamp_ns = r.time_ns("header.stamp");
  h.frame_id = r.string("header.frame_id");
  return h;
}
Vector3 vector3(WireReader& r, const char* field) {
  Vector3 v;
  v.x = r.f64(field);
  v.y = r.f64(field);
  v.z = r.f64(field);
  return v;
}
Quaternion quaternion(WireReader& r, const char* field) {
  Quaternion q;
  q.x = r.f64(field);
  q.y = r.f64(field);
  q.z = r.f64(field);
  q.w = r.f64(field);
  return q;
}
template <std::size_t N>
std::array<double, N> doubles(WireReader& r, const char* field) {
  std::array<double, N> a{};
  for (double& x : a) x = r.f64(field);
  return a;
}
std::vector<double> double_seq(WireReader& r, const char* field) {
  const std::uint32_t n = r.count(field, 8);
  std::vector<double> v(n);
  for (double& x : v) x = r.f64(field);
  return v;
}

}  // namespace

std::string normalise_type(std::string_view type) {
  std::string t(type);
  const auto at = t.find("/msg/");
  if (at != std::string::npos) t.erase(at, 4);
  return t;
}

Odometry decode_odometry(std::span<const std::uint8_t> data, WireEncoding encoding) {
  WireReader r(data, encoding);
  Odometry o;
  o.header = header(r);
  o.child_frame_id = r.string("child_frame_id");
  o.position = vector3(r, "pose.pose.position");
  o.orientation = quaternion(r, "pose.pose.orientation");
  o.pose_covariance = doubles<36>(r, "pose.covariance");
  o.linear = vector3(r, "twist.twist.linear");
  o.angular = vector3(r, "twist.twist.angular");
  o.twist_covariance = doubles<36>(r, "twist.covariance");
  return o;
}

Imu decode_imu(std::span<const std::uint8_t> data, WireEncoding encoding) {
  WireReader r(data, encoding);
  Imu m;
  m.header = header(r);
  m.orientation = quaternion(r, "orientation");
  m.orientation_covariance = doubles<9>(r, "orientation_covariance");
  m.angular_velocity = vector3(r, "angular_velocity");
  m.angular_velocity_covariance = doubles<9>(r, "angular_velocity_covariance");
  m.linear_acceleration = vector3(r, "linear_acceleration");
  m.linear_acceleration_covariance = doubles<9>(r, "linear_acceleration_covariance");
  return m;
}

NavSatFix decode_navsatfix(std::span<const std::uint8_t> data, WireEncoding encoding) {
  WireReader r(data, encoding);
  NavSatFix f;
  f.header = header(r);
  f.status = r.i8("status.status");
  f.service = r.u16("status.service");
  f.latitude_deg = r.f64("latitude");
  f.longitude_deg = r.f64("longitude");
  f.altitude_m = r.f64("altitude");
  f.position_covariance = doubles<9>(r, "position_covariance");
  f.covariance_type = r.u8("position_covariance_type");
  return f;
}

PoseStamped decode_pose_stamped(std::span<const std::uint8_t> data, WireEncoding encoding) {
  WireReader r(data, encoding);
  PoseStamped p;
  p.header = header(r);
  p.position = vector3(r, "pose.position");
  p.orientation = quaternion(r, "pose.orientation");
  return p;
}

PoseStamped decode_pose_with_covariance_stamped(std::span<const std::uint8_t> data, WireEncoding encoding) {
  WireReader r(data, encoding);
  PoseStamped p;
  p.header = header(r);
  p.position = vector3(r, "pose.pose.position");
  p.orientation = quaternion(r, "pose.pose.orientation");
  p.covariance = doubles<36>(r, "pose.covariance");
  return p;
}

TwistWithCovarianceStamped decode_twist_with_covariance_stamped(std::span<const std::uint8_t> data,
                                                                WireEncoding encoding) {
  WireReader r(data, encoding);
  TwistWithCovarianceStamped t;
  t.header = header(r);
  t.linear = vector3(r, "twist.twist.linear");
  t.angular = vector3(r, "twist.twist.angular");
  t.covariance = doubles<36>(r, "twist.covariance");
  return t;
}

TwistStamped decode_twist(std::span<const std::uint8_t> data, WireEncoding encoding) {
  WireReader r(data, encoding);
  TwistStamped t;
  t.linear = vector3(r, "linear");
  t.angular = vector3(r, "angular");
  return t;
}

TwistStamped decode_twist_stamped(std::span<const std::uint8_t> data, WireEncoding encoding) {
  WireReader r(data, encoding);
  TwistStamped t;
  t.header = header(r);
  t.linear = vector3(r, "twist.linear");
  t.angular = vector3(r, "twist.angular");
  return t;
}

JointState decode_joint_state(std::span<const std::uint8_t> data, WireEncoding encoding) {
  WireReader r(data, encoding);
  JointState j;
  j.header = header(r);
  const std::uint32_t n = r.count("name", 4);
  j.name.reserve(n);
  for (std::uint32_t i = 0; i < n; ++i) j.name.push_back(r.string("name"));
  j.position = double_seq(r, "position");
  j.velocity = double_seq(r, "velocity");
  j.effort = double_seq(r, "effort");
  return j;
}

TFMessage decode_tf_message(std::span<const std::uint8_t> data, WireEncoding encoding) {
  WireReader r(data, encoding);
  TFMessage m;
  const std::uint32_t n = r.count("transforms", 64);
  m.transforms.reserve(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    TransformStamped t;
    t.header = header(r);
    t.child_frame_id = r.string("child_frame_id");
    t.translation = vector3(r, "transform.translation");
    t.rotation = quaternion(r, "transform.rotation");
    m.transforms.push_back(std::move(t));
  }
  return m;
}

}  // namespace odotune::bags::ros
