// Which of a track's columns are its odometry: the wheels (ticks or wheel
// rates, through the nominal geometry), a body twist the drive controller
// measured, or the velocity commands (docs/track-format.md,
// `source.body_velocity`). Tools that learn or calibrate odometry need to
// know which one they read: a command leads the motion by the drive's delay
// and dynamics, a measured twist does not.
#pragma once

#include <array>
#include <optional>
#include <string_view>

#include <odotune/tracks/track.h>

namespace odotune::tracks {

enum class OdometryInput { wheels, twist, commands };
inline constexpr std::array<OdometryInput, 3> kAllOdometryInputs = {OdometryInput::wheels, OdometryInput::twist,
                                                                    OdometryInput::commands};
std::string_view to_string(OdometryInput s);  // "wheels", "twist", "commands"
bool parse_odometry_input(std::string_view text, OdometryInput* out);

// The odometry source of `track`: `requested` when given, else wheels when
// the track has ticks or wheel rates, else its v_cmd/w_cmd as its
// source.body_velocity says (measured: twist, commanded: commands). Throws
// std::invalid_argument with one line naming the track when the track lacks
// the columns of the requested source, when a v_cmd/w_cmd track does not say
// what they are and nothing was requested, or when the request contradicts
// the track's source.body_velocity.
OdometryInput track_odometry_input(const Track& track, std::optional<OdometryInput> requested = std::nullopt);

}  // namespace odotune::tracks
