#include <odotune/tracks/odometry_input.h>

#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/enum_names.h>

namespace odotune::tracks {

std::string_view to_string(OdometryInput s) {
  switch (s) {
    case OdometryInput::wheels: return "wheels";
    case OdometryInput::twist: return "twist";
    case OdometryInput::commands: return "commands";
  }
  return "wheels";
}

bool parse_odometry_input(std::string_view text, OdometryInput* out) {
  return core::parse_by_name(text, kAllOdometryInputs, out);
}

namespace {

[[noreturn]] void fail_odometry(const Track& track, const std::string& what) {
  throw std::invalid_argument(fmt::format("track '{}': {}", track.name(), what));
}

OdometryInput body_source(BodyVelocitySource b) {
  return b == BodyVelocitySource::measured ? OdometryInput::twist : OdometryInput::commands;
}

}  // namespace

OdometryInput track_odometry_input(const Track& track, std::optional<OdometryInput> requested) {
  const bool wheels = track.has_ticks() || track.has_wheel_rates();
  const auto& said = track.meta().body_velocity;
  if (!requested) {
    if (wheels) return OdometryInput::wheels;
    if (!track.has_cmd()) fail_odometry(track, "no odometry (ticks, wheel rates or v_cmd/w_cmd)");
    if (!said)
      fail_odometry(
          track,
          "v_cmd/w_cmd are its only odometry, and the track does not say whether they are commanded or "
          "measured: expected metadata '# source.body_velocity: commanded|measured' (docs/track-format.md) "
          "or --input commands|twist");
    return body_source(*said);
  }
  if (*requested == OdometryInput::wheels) {
    if (!wheels)
      fail_odometry(track, "--input wheels: expected ticks_l/ticks_r or omega_l/omega_r, the track has none");
    return *requested;
  }
  if (!track.has_cmd())
    fail_odometry(track,
                  fmt::format("--input {}: expected v_cmd/w_cmd, the track has none", to_string(*requested)));
  if (said && body_source(*said) != *requested)
    fail_odometry(track, fmt::format("--input {} contradicts the track's source.body_velocity: {}",
                                     to_string(*requested), to_string(*said)));
  return *requested;
}

}  // namespace odotune::tracks
