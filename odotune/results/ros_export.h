// Export of a tuned EKF noise configuration as a ROS 2 parameter file for
// robot_localization's `ekf_node` (cra-ros-pkg/robot_localization), and the
// matching reader used to check such a file.
//
// robot_localization's filter has a 15-element state in the order
//   x, y, z, roll, pitch, yaw, vx, vy, vz, vroll, vpitch, vyaw, ax, ay, az
// (params/ekf.yaml, comment above `process_noise_covariance`), and its
// process noise is the 15 × 15 row-major parameter `process_noise_covariance`,
// which Ekf::predict (src/ekf.cpp, "(3) Project the error forward") adds as
//   P ← J·P·Jᵀ + Δt·Q          (`estimate_error_covariance_ += delta_sec * Q`)
// so Q is a variance *rate* [unit²/s]. Measurement covariance is not a node
// parameter: robot_localization takes it from each input message's covariance
// field, so odotune's fix variances are written as comments for the position
// source's message (pose0 / odom0) only.
//
// SI throughout: metres, radians, seconds.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace odotune::results {

// Size of robot_localization's state and of process_noise_covariance.
inline constexpr int kRlStateSize = 15;
inline constexpr int kRlCovSize = kRlStateSize * kRlStateSize;  // 225
// Indices into the state (params/ekf.yaml order).
inline constexpr int kRlX = 0, kRlY = 1, kRlYaw = 5;
// Names of the 15 states, in order.
extern const std::array<const char*, kRlStateSize> kRlStateNames;
// robot_localization's default process_noise_covariance diagonal, used for
// every state odotune does not tune (all off-diagonals default to 0). Source:
// FilterBase::reset() in src/filter_base.cpp, identical to the matrix
// documented as "Defaults to the matrix below if unspecified" in
// params/ekf.yaml: 0.05 0.05 0.06 0.03 0.03 0.06 0.025 0.025 0.04 0.01 0.01
// 0.02 0.01 0.01 0.015.
extern const std::array<double, kRlStateSize> kRlDefaultProcessNoiseDiagonal;

struct RosExportInput {
  // Top-level key of the parameter file: the ekf_node's name. Letters,
  // digits, '_' and '/', not starting with a digit.
  std::string node_name = "ekf_filter_node";
  // Diagonal of process_noise_covariance for x, y [m²/s] and yaw [rad²/s]:
  // variance added per second of prediction (robot_localization multiplies
  // by Δt, see above). Must be finite and ≥ 0.
  double process_var_x_m2_per_s = 0.0;
  double process_var_y_m2_per_s = 0.0;
  double process_var_yaw_rad2_per_s = 0.0;
  // Variance of one absolute position fix in x, y [m²]; goes into the fix
  // message's pose covariance, not into the parameter file. Finite, > 0.
  double fix_var_x_m2 = 0.0;
  double fix_var_y_m2 = 0.0;
  // `frequency` parameter: rate of the filter's output/prediction loop [Hz].
  // Finite, > 0.
  double frequency_hz = 30.0;
  // `two_d_mode` parameter (planar robot: z, roll, pitch and their rates are
  // held at 0).
  bool two_d_mode = true;
  // Free text written into the header comment, e.g.
  // "odotune tune: model rq, mode 7, seed 1, track1". Newlines are flattened.
  std::string provenance;
  // The parameters as tuned (name, value in the name's unit), echoed in
  // comments so the file says where its numbers came from.
  std::vector<std::pair<std::string, double>> tuned_params;
  // How the x, y, yaw process noise was obtained from the tuned model, written
  // as comment lines (one per '\n'-separated line) in place of the rq
  // mapping explanation; empty = the rq explanation (ros_input_from_rq). Used
  // for the alpha/gyro models, whose process noise is not constant (see
  // odotune/objectives/process_noise_rate.h).
  std::string mapping_note;

  // False (with the offending field in *why) on a bad value as described
  // above.
  bool IsValid(std::string* why) const;
};

// Converts odotune's rq model to robot_localization's units:
//   r1, r2 [mm² per prediction step], r3 [rad² per prediction step] →
//   variance per second = per-step variance × steps per second
//   (odotune predicts once per odometry sample, at odometry_rate_hz), with
//   mm² → m² (× 1e-6); q1, q2 [mm²] → fix variance [m²] (× 1e-6).
// This assumes robot_localization scales Q by the prediction's Δt (Ekf::predict
// in src/ekf.cpp: `estimate_error_covariance_ += delta_sec * Q`), so that the
// variance it accumulates per second equals Q whatever its prediction rate.
// Sets frequency_hz = odometry_rate_hz and tuned_params to the five inputs
// (r1_mm2, r2_mm2, r3_rad2, q1_mm2, q2_mm2); provenance is left empty.
// Throws std::invalid_argument if odometry_rate_hz is not finite and > 0.
RosExportInput ros_input_from_rq(double r1_mm2, double r2_mm2, double r3_rad2, double q1_mm2, double q2_mm2,
                                 double odometry_rate_hz);

// The commented ROS 2 parameter file
//   NODE:
//     ros__parameters:
//       frequency: …
//       two_d_mode: …
//       process_noise_covariance: [225 numbers, 15 rows of 15]
// with x, y, yaw from `in`, robot_localization's defaults on the other
// diagonal entries and 0 off the diagonal. Every number is written as a
// double literal (ROS 2 rejects an integer where a double is declared) that
// reads back to the identical double. Throws std::invalid_argument when
// !in.IsValid().
std::string robot_localization_yaml(const RosExportInput& in);

struct RosExportParsed {
  std::string node_name;
  double frequency_hz = 0.0;
  bool two_d_mode = false;
  std::array<double, kRlCovSize> process_noise_covariance{};  // row-major 15 × 15

  // Element (row, col), 0-based.
  double at(int row, int col) const {
    return process_noise_covariance[static_cast<std::size_t>(row) * kRlStateSize +
                                    static_cast<std::size_t>(col)];
  }
};

// Reads back a parameter file: the first top-level entry holding a
// `ros__parameters` mapping, and in it `frequency`, `two_d_mode` and
// `process_noise_covariance`. Throws std::runtime_error naming `source`, the
// line (1-based, where known), what is wrong and what was expected: invalid
// YAML, no `ros__parameters`, a missing key, a value of the wrong type, or a
// matrix that is not a list of exactly 225 numbers.
RosExportParsed parse_robot_localization_yaml(const std::string& text,
                                              const std::string& source = "robot_localization YAML");

// Writes robot_localization_yaml(in) to `path` atomically: into a temporary
// file beside it, then renamed over it. On any failure (invalid input,
// missing directory, write error) throws (std::invalid_argument or
// std::runtime_error naming the path) and leaves neither `path` changed nor
// a temporary file behind.
void write_robot_localization_yaml(const RosExportInput& in, const std::filesystem::path& path);

}  // namespace odotune::results
