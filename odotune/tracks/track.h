// A track: one recording or simulation of a differential-drive robot, as
// specified in ../shared/specs/track-format.md (odotune-track/1).
//
// Contract: a Track is immutable once built. Construct it from a TrackData
// (which the reader, the importers and the simulator fill); the constructor
// checks the structural invariants (equal column lengths, strictly increasing
// time) and throws std::invalid_argument naming the broken one. Everything
// downstream takes `const Track&`.
//
// Units are SI throughout (m, rad, s, W). An absent sample ("empty cell") is
// NaN in a real-valued column and kNoTick in a tick column. A column that the
// file does not have at all is an empty vector.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace odotune::tracks {

// Real-valued columns of the format, in the order of the spec's table
// (t and the integer tick columns are held separately).
enum class Col : int {
  omega_l,
  omega_r,  // wheel angular rates [rad/s]
  v_cmd,
  w_cmd,   // commanded / base-reported body velocities [m/s, rad/s]
  gyro_z,  // yaw rate [rad/s]
  power_l,
  power_r,  // motor electrical power [W]
  v_ext,
  w_ext,  // external body-velocity measurement [m/s, rad/s]
  v_ext_var,
  w_ext_var,  // its variances [(m/s)^2, (rad/s)^2]
  aps_x,
  aps_y,  // absolute position fix [m]
  aps_var_x,
  aps_var_y,  // its variances [m^2], when known (e.g. from a NavSatFix covariance)
  gt_x,
  gt_y,
  gt_theta,  // ground-truth pose [m, m, rad]
  kCount
};
inline constexpr int kNumCols = static_cast<int>(Col::kCount);

// Column name as written in a track file header.
std::string_view column_name(Col c);
// All names a header may contain, including t, ticks_l and ticks_r.
const std::vector<std::string_view>& known_column_names();

inline constexpr std::int64_t kNoTick = std::numeric_limits<std::int64_t>::min();

// What a track's body velocities v_cmd, w_cmd are (metadata
// `source.body_velocity`, docs/track-format.md): the velocities the robot was
// commanded (they lead the motion, through its drive's delay and dynamics) or
// the twist its drive controller measured and reported (encoders through the
// controller's own kinematics).
enum class BodyVelocitySource { commanded, measured };
std::string_view to_string(BodyVelocitySource s);  // "commanded", "measured"
bool parse_body_velocity_source(std::string_view text, BodyVelocitySource* out);

// The robot's nominal parameters and any other metadata of a track.
struct TrackMeta {
  std::string name;                     // short name; file stem by default
  std::string origin;                   // "recorded", "simulated" or ""
  std::optional<double> ticks_per_rev;  // encoder counts per wheel revolution
  std::optional<double> wheel_radius_left_m;
  std::optional<double> wheel_radius_right_m;
  std::optional<double> wheel_base_m;
  // source.body_velocity: what v_cmd/w_cmd are; nullopt when the file does
  // not say (the spec allows either).
  std::optional<BodyVelocitySource> body_velocity;
  // Every other `# key: value` line, in file order (e.g. sim.seed, source).
  std::vector<std::pair<std::string, std::string>> extra;

  // Value of an extra key, if present.
  std::optional<std::string> get(std::string_view key) const;
};

// Mutable staging area for building a Track.
struct TrackData {
  TrackMeta meta;
  std::vector<double> t;                           // [s], strictly increasing
  std::array<std::vector<double>, kNumCols> cols;  // each empty or t.size() long
  std::vector<std::int64_t> ticks_l, ticks_r;      // each empty or t.size() long

  std::vector<double>& col(Col c) { return cols[static_cast<int>(c)]; }
  // Makes column c present (all cells empty) if it is not already.
  std::vector<double>& ensure(Col c);
};

class Track {
 public:
  // Throws std::invalid_argument on a broken invariant (see file comment).
  explicit Track(TrackData data);

  const TrackMeta& meta() const { return d_.meta; }
  const std::string& name() const { return d_.meta.name; }
  std::size_t size() const { return d_.t.size(); }
  const std::vector<double>& t() const { return d_.t; }
  double duration_s() const { return d_.t.empty() ? 0.0 : d_.t.back() - d_.t.front(); }

  bool has(Col c) const { return !d_.cols[static_cast<int>(c)].empty(); }
  // The whole column (empty vector if absent; NaN marks an empty cell).
  const std::vector<double>& col(Col c) const { return d_.cols[static_cast<int>(c)]; }
  bool has_ticks() const { return !d_.ticks_l.empty() && !d_.ticks_r.empty(); }
  const std::vector<std::int64_t>& ticks_l() const { return d_.ticks_l; }
  const std::vector<std::int64_t>& ticks_r() const { return d_.ticks_r; }

  bool has_wheel_rates() const { return has(Col::omega_l) && has(Col::omega_r); }
  bool has_cmd() const { return has(Col::v_cmd) && has(Col::w_cmd); }
  bool has_odometry() const { return has_ticks() || has_wheel_rates() || has_cmd(); }
  bool has_gt() const { return has(Col::gt_x) && has(Col::gt_y); }
  bool has_aps() const { return has(Col::aps_x) && has(Col::aps_y); }

  // True when row i holds a sample of column c.
  bool at(Col c, std::size_t i) const {
    const auto& v = col(c);
    return !v.empty() && !std::isnan(v[i]);
  }

  const TrackData& data() const { return d_; }

 private:
  TrackData d_;
};

}  // namespace odotune::tracks
