// LSTM nets as JSON (odotune/results/lstm_json.h): exact round trip, and every bad
// field rejected with a one-line message naming it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

#include <odotune/core/counter_rng.h>
#include <odotune/results/lstm_json.h>

namespace odotune::results {
namespace {

template <int I, int H>
learned::LstmNet<I, H> random_net(std::uint64_t seed) {
  learned::LstmNet<I, H> net;
  // Awkward doubles (full 53-bit mantissas, tiny and huge magnitudes) so that
  // a lossy writer would show.
  for (int n = 0; n < net.kWeights; ++n)
    net.weights[n] = (core::counter_uniform01(seed, 1, static_cast<std::uint64_t>(n), 0, 5) - 0.5) *
                     std::pow(10.0, (n % 7) - 3);
  for (int k = 0; k < I; ++k) {
    net.input_mean[k] = core::counter_uniform01(seed, 2, static_cast<std::uint64_t>(k), 0, 5) * 100.0 - 50.0;
    net.input_sd[k] = core::counter_uniform01(seed, 3, static_cast<std::uint64_t>(k), 0, 5) + 1e-9;
  }
  net.output_mean = 1.0 / 3.0;
  net.output_sd = 0.1;
  net.window = 17;
  return net;
}

template <int I, int H>
void expect_identical(const learned::LstmNet<I, H>& a, const learned::LstmNet<I, H>& b) {
  EXPECT_EQ(0, std::memcmp(a.weights.data(), b.weights.data(), sizeof(a.weights)));
  EXPECT_EQ(0, std::memcmp(a.input_mean.data(), b.input_mean.data(), sizeof(a.input_mean)));
  EXPECT_EQ(0, std::memcmp(a.input_sd.data(), b.input_sd.data(), sizeof(a.input_sd)));
  EXPECT_EQ(a.output_mean, b.output_mean);
  EXPECT_EQ(a.output_sd, b.output_sd);
  EXPECT_EQ(a.window, b.window);
  EXPECT_EQ(a.activation, b.activation);
}

TEST(LstmJson, RoundTripIsExactThroughText) {
  auto v = random_net<3, 5>(1);
  const std::string text = lstm_to_json(v).dump();
  expect_identical(v, lstm_from_json<3, 5>(nlohmann::json::parse(text)));

  auto s = random_net<5, 10>(2);
  s.activation = learned::OutputActivation::relu;
  const nlohmann::json j = s;  // ADL hook
  const auto back = nlohmann::json::parse(j.dump(2)).get<learned::SlipNet>();
  expect_identical(s, back);
  EXPECT_EQ(j.at("format"), "odotune-lstm/1");
  EXPECT_EQ(j.at("inputs"), 5);
  EXPECT_EQ(j.at("hidden"), 10);
  EXPECT_EQ(j.at("activation"), "relu");
  EXPECT_EQ(j.at("weights").size(), 651u);
}

std::string lstm_read_error(const nlohmann::json& j) {
  try {
    lstm_from_json<3, 5>(j);
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    return what;
  }
  ADD_FAILURE() << "accepted: " << j.dump();
  return {};
}

void expect_rejected(const nlohmann::json& j, const std::string& names) {
  const std::string msg = lstm_read_error(j);
  EXPECT_NE(msg.find(names), std::string::npos) << "message '" << msg << "' should name " << names;
}

TEST(LstmJson, EveryBadFieldIsNamed) {
  const nlohmann::json good = lstm_to_json(random_net<3, 5>(3));
  auto with = [&](const char* key, nlohmann::json value) {
    nlohmann::json j = good;
    j[key] = std::move(value);
    return j;
  };
  auto without = [&](const char* key) {
    nlohmann::json j = good;
    j.erase(key);
    return j;
  };
  expect_rejected(with("format", "odotune-lstm/2"), "'format'");
  expect_rejected(with("format", 1), "'format'");
  expect_rejected(with("inputs", 5), "'inputs'");
  expect_rejected(with("hidden", 10), "'hidden'");
  expect_rejected(with("hidden", "5"), "'hidden'");
  expect_rejected(with("activation", "tanh"), "'activation'");
  expect_rejected(with("window", 0), "'window'");
  expect_rejected(with("window", 2.5), "'window'");
  expect_rejected(with("input_mean", {1.0, 2.0}), "'input_mean'");
  expect_rejected(with("input_sd", {1.0, 0.0, 1.0}), "'input_sd[1]'");
  expect_rejected(with("input_sd", {1.0, 1.0, -2.0}), "'input_sd[2]'");
  expect_rejected(with("output_sd", 0.0), "'output_sd'");
  expect_rejected(with("output_mean", nullptr), "'output_mean'");  // how nlohmann writes NaN
  expect_rejected(with("output_mean", "1"), "'output_mean'");
  nlohmann::json short_weights = good;
  short_weights["weights"].erase(0);
  expect_rejected(short_weights, "'weights'");
  nlohmann::json null_weight = good;
  null_weight["weights"][42] = nullptr;
  expect_rejected(null_weight, "'weights[42]'");
  expect_rejected(with("weights", 1.0), "'weights'");
  for (const char* key : {"format", "inputs", "hidden", "activation", "window", "input_mean", "input_sd",
                          "output_mean", "output_sd", "weights"})
    expect_rejected(without(key), std::string("'") + key + "'");
  EXPECT_NO_THROW((lstm_from_json<3, 5>(good)));
  EXPECT_NE(lstm_read_error(nlohmann::json::array()).find("object"), std::string::npos);
}

TEST(LstmJson, WritingAnInvalidNetThrows) {
  auto net = random_net<3, 5>(4);
  net.weights[3] = std::nan("");
  EXPECT_THROW(lstm_to_json(net), std::invalid_argument);
}

}  // namespace
}  // namespace odotune::results
