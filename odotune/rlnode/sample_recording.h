// A recording that is not a bag: plain time-stamped samples, as a robot's
// drivers would publish them, turned into the messages the node's callbacks
// take (odotune/rlnode/recording.h prepares them alike). What each stream is to the
// filter follows from the parameter file's inputs (sample_roles):
//   odometry  the one odomN or twistN that fuses velocities only: a
//             nav_msgs/Odometry (or TwistWithCovarianceStamped) in base_link
//             with vx and vyaw and a diagonal twist covariance;
//   gyro      the one imuN, fusing angular velocities only: a sensor_msgs/Imu
//             without orientation or acceleration (covariance[0] = −1);
//   fixes     the one odomN or poseN that fuses position only: position fixes
//             already in the world frame, each with its variances, fused as
//             navsat_transform_node's output would be under an identity
//             transform (so that held-out fixes and outages score as for a bag).
// Any other input of the file, or a role the samples do not have, is refused
// in one line naming the input and what was expected.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <odotune/rlnode/params.h>
#include <odotune/rlnode/recording.h>

namespace odotune::rlnode {

struct TwistSample {
  std::int64_t stamp_ns = 0;
  double vx = 0.0, vyaw = 0.0;  // [m/s], [rad/s], base_link
};
struct RateSample {
  std::int64_t stamp_ns = 0;
  double vyaw = 0.0;  // [rad/s]
};
struct FixSample {
  std::int64_t stamp_ns = 0;
  double x = 0.0, y = 0.0;          // [m], world frame
  double var_x = 0.0, var_y = 0.0;  // [m²], > 0
};

struct SampleStreams {
  std::string name;  // what the samples came from (a track's file), for messages
  std::vector<TwistSample> odometry;
  double odometry_var_vx = 0.0, odometry_var_vyaw = 0.0;  // the twist covariance's diagonal [(m/s)², (rad/s)²]
  std::vector<RateSample> gyro;                           // empty: none
  double gyro_var = 0.0;                                  // [(rad/s)²]
  std::vector<FixSample> fixes;                           // empty: none
};

// The file's input (index into RlParams::sensors) each stream is, −1 when the
// file fuses none of that kind.
struct SampleRoles {
  int odometry = -1, gyro = -1, fixes = -1;
};
// Throws std::invalid_argument (one line naming `what`, the file and the
// input) for an input that is none of the three, a role held by two inputs,
// or a file without an odometry input.
SampleRoles sample_roles(const RlParams& params, const std::string& what);

// The recording, on the samples' clock (origin 0: a user's seconds are the
// samples' own). Only samples stamped at or after `start_ns` are given to the
// node. Throws std::invalid_argument (one line) as sample_roles does, and
// when the file fuses a stream the samples do not have.
Recording load_sample_recording(const RlParams& params, const SampleStreams& streams, std::int64_t start_ns);

}  // namespace odotune::rlnode
