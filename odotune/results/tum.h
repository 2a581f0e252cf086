// Trajectories in the TUM RGB-D benchmark's text format, which evo
// (evo_traj, evo_ape, evo_rpe) and most SLAM evaluation tools read: one line
// per pose, "t x y z qx qy qz qw" (seconds, metres, a unit quaternion), here
// with z = 0 and the rotation about z by the heading θ: (0, 0, sin θ/2,
// cos θ/2). A header comment names what the trajectory is. Written atomically.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <odotune/objectives/replay.h>

namespace odotune::results {

// `time_offset_s` is added to every t (e.g. a track's absolute start,
// source.t0_ns, so that the file shares the recording's clock).
void write_tum(const std::filesystem::path& path, const std::vector<objectives::TrajectoryPoint>& points,
               const std::string& comment, double time_offset_s = 0.0);

}  // namespace odotune::results
