// JSON form of the LSTM nets (odotune/learned/lstm.h): weights, standardisation and
// shape, so that a net trained offline (odotune/learned/lstm_training.h) is saved
// and loaded on the robot.
//
//   {
//     "format": "odotune-lstm/1",
//     "inputs": I, "hidden": H,           // must match the LstmNet<I, H> read into
//     "activation": "linear" | "relu",
//     "window": 20,                        // samples per window, 1..LstmNet::kMaxWindow
//     "input_mean": [I numbers], "input_sd": [I numbers > 0],
//     "output_mean": number, "output_sd": number > 0,
//     "weights": [LstmLayout<I, H>::kCount numbers]   // layout: odotune/learned/lstm.h (Keras order)
//   }
//
// Doubles are written in nlohmann's shortest round-trip form, so weights read
// back are bit-identical. Reading validates every field and throws
// std::invalid_argument with one line naming the JSON field and what was
// expected (missing, wrong type, wrong shape or count, non-finite, sd ≤ 0,
// wrong format tag).
#pragma once

#include <nlohmann/json.hpp>

#include <odotune/learned/lstm.h>
#include <odotune/learned/odometry_net.h>

namespace odotune::results {

inline constexpr const char* kLstmJsonFormat = "odotune-lstm/1";

// Throws std::invalid_argument when !net.IsValid() (a non-finite value would
// otherwise be written as null).
template <int I, int H>
nlohmann::json lstm_to_json(const learned::LstmNet<I, H>& net);

template <int I, int H>
learned::LstmNet<I, H> lstm_from_json(const nlohmann::json& j);

// An OdometryNet: its net's JSON; reading picks the size from "hidden"
// (one of kOdometryNetUnits, else std::invalid_argument naming the field).
nlohmann::json odometry_net_to_json(const learned::OdometryNet& net);
learned::OdometryNet odometry_net_from_json(const nlohmann::json& j);

}  // namespace odotune::results

// nlohmann's conversion hooks (`nlohmann::json j = net;`, `j.get<VelocityNet>()`),
// forwarding to the functions above (instantiated for <3, 3>, <3, 5>, <3, 8> and
// <5, 10>). A serializer specialisation rather than to_json/from_json found by
// argument-dependent lookup, which would have to live in learned's namespace.
template <int I, int H>
struct nlohmann::adl_serializer<odotune::learned::LstmNet<I, H>> {
  static void to_json(json& j, const odotune::learned::LstmNet<I, H>& net) {
    j = odotune::results::lstm_to_json(net);
  }
  static void from_json(const json& j, odotune::learned::LstmNet<I, H>& net) {
    net = odotune::results::lstm_from_json<I, H>(j);
  }
};
