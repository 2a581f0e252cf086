// The learned-odometry model file, format "odotune-learned/1", written by
// `odotune learn train|retrain` and `odotune study learned` and read by
// `odotune learn eval|retrain`: the velocity nets of Fariña et al., Sensors
// 2023, 23, 961 (odotune/learned/learned_odometry.h), optionally the slip detector
// (odotune/learned/slip_detector.h), and where they came from.
//
//   {
//     "format": "odotune-learned/1",
//     "odometry": {"rate_hz": 10, "ticks_per_rev": 8800,   // 0 for twist and commands
//                  "target": "velocity" | "correction",     // absent: velocity
//                  "input": "wheels" | "twist" | "commands", // absent: wheels
//                  "features": "paper" | "channel" | "both", // absent: paper (velocity nets only)
//                  "gyro": false,                           // absent: false
//                  "v_beats_kinematic": true, "w_beats_kinematic": true,  // absent: true
//                  "v_validation_mae": …, "w_validation_mae": …,
//                  "v_kinematic_mae": …, "w_kinematic_mae": …, // absent: 0 (unknown)
//                  "v_net": {…}, "w_net": {…}},            // odotune/results/lstm_json.h (3, 5 or 8 units)
//     "detector": {"floor_var_v": …, "floor_var_w": …, "previous_lag": 1,
//                  "drive": "power" | "commands" | "none",   // absent: power
//                  "input": "wheels" | …,  "flag_var_v": …, "flag_var_w": …,  // absent: wheels, 0
//                  "max_log_ratio_v": …, "max_log_ratio_w": …,
//                  "v_net": {…}, "w_net": {…}},            // optional
//     "provenance": {"tracks": [names], "slip_tracks": [names], "seed": 1,
//                    "odometry": TRAINING, "detector": TRAINING (optional),
//                    "retrains": 0, "retrain_tracks": [names], "created_by": "…",
//                    "selection": {…}}   // correction nets: the cross-validation (odotune/studies/learn_job.h), kept as written
//   }
//   TRAINING = {"train_windows", "validation_windows", "seconds",
//               "v": {"iterations", "train_mae", "validation_mae"}, "w": {…}}
//
// Numbers are written in shortest round-trip form, so a file reads back to
// the same doubles (a round trip is exact). MAEs that are unknown are null.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <odotune/learned/learned_odometry.h>
#include <odotune/learned/lstm_training.h>
#include <odotune/learned/slip_detector.h>

namespace odotune::results {

inline constexpr const char* kLearnedModelFormat = "odotune-learned/1";

// One net's training [raw target units].
struct NetTrainingRecord {
  int iterations = 0;
  double train_mae = std::numeric_limits<double>::quiet_NaN();
  double validation_mae = std::numeric_limits<double>::quiet_NaN();
};

// A pair of nets' training (velocity nets or detector).
struct ModelTrainingRecord {
  NetTrainingRecord v, w;
  std::size_t train_windows = 0, validation_windows = 0;
  double seconds = 0.0;  // wall time of both nets
};

struct LearnedModelProvenance {
  std::vector<std::string> tracks;       // the velocity nets' training tracks (names)
  std::vector<std::string> slip_tracks;  // the detector's (empty without one)
  std::uint64_t seed = 0;                // Ceres initial weights
  ModelTrainingRecord odometry;
  std::optional<ModelTrainingRecord> detector;
  int retrains = 0;                         // online refits since training (`learn retrain`)
  std::vector<std::string> retrain_tracks;  // where they happened (names)
  std::string created_by;                   // the command line
  // Correction nets: how their settings were chosen and what the
  // cross-validation measured (written by odotune/studies/learn_job.cpp; read back
  // as it is, an object).
  std::optional<nlohmann::json> selection;
};

struct LearnedModelFile {
  learned::LearnedOdometryModel odometry;
  std::optional<learned::SlipDetectorModel> detector;
  LearnedModelProvenance provenance;
};

ModelTrainingRecord training_record(const learned::LstmTrainingSummary& v,
                                    const learned::LstmTrainingSummary& w, std::size_t train_windows,
                                    std::size_t validation_windows, double seconds);

nlohmann::json learned_model_json(const LearnedModelFile& model);

// Parses and validates every field. Throws std::invalid_argument with one
// line "FILE: FIELD: what is wrong; expected …" (FIELD a JSON path such as
// odometry.v_net.weights[3] or provenance.seed).
LearnedModelFile parse_learned_model(const nlohmann::json& j, const std::string& file);

// Writes the file atomically (odotune/core/atomic_file.h); std::runtime_error on failure.
void write_learned_model(const std::filesystem::path& path, const LearnedModelFile& model);
// Reads and parses; std::invalid_argument (one line naming the file) for a
// missing or unreadable file, bad JSON or a bad field.
LearnedModelFile read_learned_model(const std::filesystem::path& path);

}  // namespace odotune::results
