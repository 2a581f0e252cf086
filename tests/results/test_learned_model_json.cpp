// The learned-model file "odotune-learned/1" (odotune/results/learned_model_json.h):
// an exact round trip, and one-line errors naming the file and the JSON field
// for every kind of bad field.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>

#include <odotune/results/learned_model_json.h>
#include <odotune/results/lstm_json.h>

#include "support/temp_dir.h"

namespace odotune::results {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing_support::TempDir;

// Seeded random values spanning magnitudes, so that a lossy number format
// would show.
template <class Net>
Net random_net(std::mt19937_64& rng, learned::OutputActivation act) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Net n;
  for (double& w : n.weights) w = u(rng) * std::pow(10.0, 3.0 * u(rng));
  for (double& m : n.input_mean) m = 100.0 * u(rng);
  for (double& s : n.input_sd) s = 0.1 + std::abs(u(rng)) * 50.0;
  n.output_mean = u(rng) / 3.0;
  n.output_sd = 0.1 + 0.2 + std::abs(u(rng));
  n.activation = act;
  n.window = 20;
  return n;
}

LearnedModelFile sample_model(bool detector) {
  std::mt19937_64 rng(42);
  LearnedModelFile m;
  // Correction nets of 3 units on wheels with the gyro (the other sizes and
  // inputs: VelocityNetsAndOtherSizesAndInputs).
  m.odometry.v_net = random_net<learned::OdometryNet::Net3>(rng, learned::OutputActivation::linear);
  m.odometry.w_net = random_net<learned::OdometryNet::Net3>(rng, learned::OutputActivation::linear);
  m.odometry.rate_hz = 10.0;
  m.odometry.ticks_per_rev = 8800.0;
  m.odometry.v_validation_mae = 0.1 + 0.2;  // not exactly 0.3
  m.odometry.w_validation_mae = 1.0 / 3.0;
  m.odometry.target = learned::LearnedTarget::correction;
  m.odometry.features = learned::LearnedFeatures::both;
  m.odometry.gyro = true;
  m.odometry.w_beats_kinematic = false;
  if (detector) {
    learned::SlipDetectorModel d;
    d.v_net = random_net<learned::SlipNet>(rng, learned::OutputActivation::linear);
    d.w_net = random_net<learned::SlipNet>(rng, learned::OutputActivation::relu);
    d.floor_var_v = 1.234567890123e-5;
    d.floor_var_w = 2e-300;
    d.previous_lag = 3;
    d.max_log_ratio_v = 9.87654321;
    d.max_log_ratio_w = 11.5;
    d.drive = learned::SlipDrive::commands;
    d.flag_var_v = 3.25e-4;
    d.flag_var_w = 1.0 / 7.0;
    m.detector = d;
  }
  auto& p = m.provenance;
  p.tracks = {"wheelchair_learn", "ünïcode track"};
  p.slip_tracks = detector ? std::vector<std::string>{"wheelchair_slip"} : std::vector<std::string>{};
  p.seed = 18446744073709551615ULL;  // the largest seed survives
  p.odometry.v = {61, 0.00123, 0.0456};
  p.odometry.w = {12, 0.0789, std::nan("")};
  p.odometry.train_windows = 700;
  p.odometry.validation_windows = 300;
  p.odometry.seconds = 1.5;
  if (detector) p.detector = ModelTrainingRecord{{5, 0.5, 0.6}, {6, 0.7, 0.8}, 90, 40, 2.25};
  p.retrains = 4;
  p.retrain_tracks = {"wheelchair_learn_step"};
  p.created_by = "odotune learn train --track a.csv --model-out m.json";
  p.selection = json{{"validation", "recordings"}, {"folds", 2}};
  return m;
}

template <class Net>
void expect_same_net(const Net& a, const Net& b, const char* what) {
  EXPECT_EQ(a.weights, b.weights) << what;
  EXPECT_EQ(a.input_mean, b.input_mean) << what;
  EXPECT_EQ(a.input_sd, b.input_sd) << what;
  EXPECT_EQ(a.output_mean, b.output_mean) << what;
  EXPECT_EQ(a.output_sd, b.output_sd) << what;
  EXPECT_EQ(a.activation, b.activation) << what;
  EXPECT_EQ(a.window, b.window) << what;
}

void expect_same_net_record(const NetTrainingRecord& a, const NetTrainingRecord& b) {
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(std::isnan(a.train_mae), std::isnan(b.train_mae));
  if (!std::isnan(a.train_mae)) {
    EXPECT_EQ(a.train_mae, b.train_mae);
  }
  EXPECT_EQ(std::isnan(a.validation_mae), std::isnan(b.validation_mae));
  if (!std::isnan(a.validation_mae)) {
    EXPECT_EQ(a.validation_mae, b.validation_mae);
  }
}

TEST(LearnedModelJson, RoundTripIsExact) {
  TempDir dir("learned_model");
  const LearnedModelFile m = sample_model(true);
  results::write_learned_model(dir / "m.json", m);
  const LearnedModelFile r = results::read_learned_model(dir / "m.json");
  EXPECT_TRUE(m.odometry.v_net == r.odometry.v_net);
  EXPECT_TRUE(m.odometry.w_net == r.odometry.w_net);
  EXPECT_EQ(r.odometry.v_net.units(), 3);
  EXPECT_EQ(r.odometry.features, learned::LearnedFeatures::both);
  EXPECT_EQ(r.odometry.input, tracks::OdometryInput::wheels);
  EXPECT_TRUE(r.odometry.gyro);
  ASSERT_TRUE(r.provenance.selection.has_value());
  EXPECT_EQ(r.provenance.selection->at("folds"), 2);
  EXPECT_EQ(r.odometry.rate_hz, 10.0);
  EXPECT_EQ(r.odometry.ticks_per_rev, 8800.0);
  EXPECT_EQ(r.odometry.v_validation_mae, 0.1 + 0.2);
  EXPECT_EQ(r.odometry.w_validation_mae, 1.0 / 3.0);
  EXPECT_EQ(r.odometry.target, learned::LearnedTarget::correction);
  EXPECT_TRUE(r.odometry.v_beats_kinematic);
  EXPECT_FALSE(r.odometry.w_beats_kinematic);
  ASSERT_TRUE(r.detector.has_value());
  expect_same_net(m.detector->v_net, r.detector->v_net, "detector.v_net");
  expect_same_net(m.detector->w_net, r.detector->w_net, "detector.w_net");
  EXPECT_EQ(r.detector->floor_var_v, 1.234567890123e-5);
  EXPECT_EQ(r.detector->floor_var_w, 2e-300);
  EXPECT_EQ(r.detector->previous_lag, 3);
  EXPECT_EQ(r.detector->max_log_ratio_v, 9.87654321);
  EXPECT_EQ(r.detector->max_log_ratio_w, 11.5);
  EXPECT_EQ(r.detector->drive, learned::SlipDrive::commands);
  EXPECT_EQ(r.detector->input, tracks::OdometryInput::wheels);
  EXPECT_EQ(r.detector->flag_var_v, 3.25e-4);
  EXPECT_EQ(r.detector->flag_var_w, 1.0 / 7.0);
  const auto& p = r.provenance;
  EXPECT_EQ(p.tracks, m.provenance.tracks);
  EXPECT_EQ(p.slip_tracks, m.provenance.slip_tracks);
  EXPECT_EQ(p.seed, 18446744073709551615ULL);
  expect_same_net_record(p.odometry.v, m.provenance.odometry.v);
  expect_same_net_record(p.odometry.w, m.provenance.odometry.w);  // NaN validation MAE → null → NaN
  EXPECT_EQ(p.odometry.train_windows, 700u);
  EXPECT_EQ(p.odometry.validation_windows, 300u);
  EXPECT_EQ(p.odometry.seconds, 1.5);
  ASSERT_TRUE(p.detector.has_value());
  expect_same_net_record(p.detector->w, m.provenance.detector->w);
  EXPECT_EQ(p.detector->train_windows, 90u);
  EXPECT_EQ(p.retrains, 4);
  EXPECT_EQ(p.retrain_tracks, m.provenance.retrain_tracks);
  EXPECT_EQ(p.created_by, m.provenance.created_by);
  // Writing what was read gives the same bytes.
  results::write_learned_model(dir / "again.json", r);
  std::ifstream a(dir / "m.json"), b(dir / "again.json");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(a), {}),
            std::string(std::istreambuf_iterator<char>(b), {}));
}

TEST(LearnedModelJson, DetectorIsOptional) {
  const LearnedModelFile m = sample_model(false);
  const json j = learned_model_json(m);
  EXPECT_EQ(j.at("format"), "odotune-learned/1");
  EXPECT_FALSE(j.contains("detector"));
  EXPECT_FALSE(j.at("provenance").contains("detector"));
  const LearnedModelFile r = results::parse_learned_model(j, "m.json");
  EXPECT_FALSE(r.detector.has_value());
  EXPECT_FALSE(r.provenance.detector.has_value());
  EXPECT_TRUE(m.odometry.w_net == r.odometry.w_net);
}

// The paper's velocity nets (5 units), and correction nets of 8 units on
// commands (no ticks_per_rev), read back as written.
TEST(LearnedModelJson, VelocityNetsAndOtherSizesAndInputs) {
  std::mt19937_64 rng(7);
  LearnedModelFile paper = sample_model(false);
  paper.odometry.target = learned::LearnedTarget::velocity;
  paper.odometry.features = learned::LearnedFeatures::paper;
  paper.odometry.gyro = false;
  paper.odometry.w_beats_kinematic = true;
  paper.odometry.v_net = random_net<learned::VelocityNet>(rng, learned::OutputActivation::linear);
  paper.odometry.w_net = random_net<learned::VelocityNet>(rng, learned::OutputActivation::linear);
  LearnedModelFile r = results::parse_learned_model(results::learned_model_json(paper), "m.json");
  EXPECT_EQ(r.odometry.target, learned::LearnedTarget::velocity);
  EXPECT_EQ(r.odometry.v_net.units(), 5);
  EXPECT_TRUE(r.odometry.v_net == paper.odometry.v_net);

  LearnedModelFile cmd = sample_model(false);
  cmd.odometry.input = tracks::OdometryInput::commands;
  cmd.odometry.ticks_per_rev = 0.0;
  cmd.odometry.features = learned::LearnedFeatures::channel;
  cmd.odometry.v_net = random_net<learned::OdometryNet::Net8>(rng, learned::OutputActivation::linear);
  cmd.odometry.w_net = random_net<learned::OdometryNet::Net8>(rng, learned::OutputActivation::linear);
  r = results::parse_learned_model(results::learned_model_json(cmd), "m.json");
  EXPECT_EQ(r.odometry.input, tracks::OdometryInput::commands);
  EXPECT_EQ(r.odometry.features, learned::LearnedFeatures::channel);
  EXPECT_EQ(r.odometry.w_net.units(), 8);
  EXPECT_TRUE(r.odometry.w_net == cmd.odometry.w_net);
}

// A file written before the nets' target and verdict were recorded holds the
// paper's velocity nets, which are taken as they are.
TEST(LearnedModelJson, OlderFilesAreVelocityNets) {
  json j = learned_model_json(sample_model(false));
  std::mt19937_64 rng(3);
  j["odometry"]["v_net"] = lstm_to_json(random_net<learned::VelocityNet>(rng,
                                                                         learned::OutputActivation::linear));
  j["odometry"]["w_net"] = lstm_to_json(random_net<learned::VelocityNet>(rng,
                                                                         learned::OutputActivation::linear));
  for (const char* key : {"target", "v_beats_kinematic", "w_beats_kinematic", "input", "features", "gyro"})
    j["odometry"].erase(key);
  const LearnedModelFile r = results::parse_learned_model(j, "m.json");
  EXPECT_EQ(r.odometry.target, learned::LearnedTarget::velocity);
  EXPECT_EQ(r.odometry.features, learned::LearnedFeatures::paper);
  EXPECT_EQ(r.odometry.input, tracks::OdometryInput::wheels);
  EXPECT_TRUE(r.odometry.v_beats_kinematic);
  EXPECT_TRUE(r.odometry.w_beats_kinematic);
  // A correction model written before the features were recorded is refused.
  j["odometry"]["target"] = "correction";
  try {
    results::parse_learned_model(j, "m.json");
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("odometry.features"), std::string::npos) << e.what();
  }
}

struct BadCase {
  const char* name;
  std::function<void(json&)> mutate;
  const char* field;  // must appear in the message
};

TEST(LearnedModelJson, BadFieldsAreOneLineErrorsNamingFileAndField) {
  const json good = learned_model_json(sample_model(true));
  const std::vector<BadCase> cases = {
      {"wrong format", [](json& j) { j["format"] = "odotune-learned/2"; }, "format"},
      {"no format", [](json& j) { j.erase("format"); }, "format"},
      {"missing rate", [](json& j) { j["odometry"].erase("rate_hz"); }, "odometry.rate_hz"},
      {"negative rate", [](json& j) { j["odometry"]["rate_hz"] = -10; }, "odometry.rate_hz"},
      {"text ticks", [](json& j) { j["odometry"]["ticks_per_rev"] = "8800"; }, "odometry.ticks_per_rev"},
      {"negative mae", [](json& j) { j["odometry"]["w_validation_mae"] = -0.1; }, "odometry.w_validation_mae"},
      {"bad weight", [](json& j) { j["odometry"]["v_net"]["weights"][3] = "x"; }, "odometry.v_net"},
      {"short weights", [](json& j) { j["odometry"]["w_net"]["weights"].erase(0); }, "odometry.w_net"},
      {"slip net as velocity net", [](json& j) { j["odometry"]["v_net"] = j["detector"]["v_net"]; },
       "odometry.v_net"},
      {"unknown target", [](json& j) { j["odometry"]["target"] = "residual"; }, "odometry.target"},
      {"unknown input", [](json& j) { j["odometry"]["input"] = "lidar"; }, "odometry.input"},
      {"unknown features", [](json& j) { j["odometry"]["features"] = "all"; }, "odometry.features"},
      {"gyro not a boolean", [](json& j) { j["odometry"]["gyro"] = "yes"; }, "odometry.gyro"},
      {"four units", [](json& j) { j["odometry"]["v_net"]["hidden"] = 4; }, "odometry.v_net"},
      {"nets of two sizes",
       [](json& j) {
         std::mt19937_64 rng(5);
         j["odometry"]["w_net"] = lstm_to_json(
             random_net<learned::VelocityNet>(rng, learned::OutputActivation::linear));
       },
       "odometry"},
      {"velocity nets on commands",
       [](json& j) {
         j["odometry"]["target"] = "velocity";
         j["odometry"]["features"] = "paper";
         j["odometry"]["gyro"] = false;
         j["odometry"]["input"] = "commands";
       },
       "odometry"},
      {"verdict not a boolean", [](json& j) { j["odometry"]["v_beats_kinematic"] = 1; },
       "odometry.v_beats_kinematic"},
      {"relu velocity net", [](json& j) { j["odometry"]["v_net"]["activation"] = "relu"; }, "odometry.v_net"},
      {"zero floor", [](json& j) { j["detector"]["floor_var_w"] = 0; }, "detector.floor_var_w"},
      {"unknown drive", [](json& j) { j["detector"]["drive"] = "current"; }, "detector.drive"},
      {"zero lag", [](json& j) { j["detector"]["previous_lag"] = 0; }, "detector.previous_lag"},
      {"fractional lag", [](json& j) { j["detector"]["previous_lag"] = 1.5; }, "detector.previous_lag"},
      {"bad detector net", [](json& j) { j["detector"]["w_net"]["input_sd"][0] = -1; }, "detector.w_net"},
      {"no provenance", [](json& j) { j.erase("provenance"); }, "provenance"},
      {"negative seed", [](json& j) { j["provenance"]["seed"] = -1; }, "provenance.seed"},
      {"tracks not a list", [](json& j) { j["provenance"]["tracks"] = "a"; }, "provenance.tracks"},
      {"track not a string", [](json& j) { j["provenance"]["slip_tracks"] = {1}; },
       "provenance.slip_tracks[0]"},
      {"bad summary", [](json& j) { j["provenance"]["odometry"]["v"]["train_mae"] = "x"; },
       "provenance.odometry.v.train_mae"},
      {"bad detector summary", [](json& j) { j["provenance"]["detector"].erase("train_windows"); },
       "provenance.detector.train_windows"},
      {"not an object", [](json& j) { j = json::array(); }, "(top level)"},
  };
  for (const BadCase& c : cases) {
    json j = good;
    c.mutate(j);
    try {
      results::parse_learned_model(j, "models/bad.json");
      ADD_FAILURE() << c.name << ": expected an error";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("models/bad.json: ", 0), 0u) << c.name << ": " << what;
      EXPECT_NE(what.find(c.field), std::string::npos) << c.name << ": " << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << c.name << ": " << what;
    }
  }
  // The unmodified document parses (the cases above fail for their own reason).
  EXPECT_NO_THROW(results::parse_learned_model(good, "models/good.json"));
}

TEST(LearnedModelJson, UnreadableFilesAreOneLineErrors) {
  TempDir dir("learned_model");
  for (const auto& [content, needle] : {std::pair<std::string, std::string>{"{ \"format\": ", "not valid JSON"},
                                        std::pair<std::string, std::string>{"", "not valid JSON"}}) {
    std::ofstream(dir / "x.json") << content;
    try {
      results::read_learned_model(dir / "x.json");
      ADD_FAILURE() << "expected an error for '" << content << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("x.json"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(results::read_learned_model(dir / "missing.json"), std::invalid_argument);
  // Writing into a folder that does not exist fails and leaves nothing.
  EXPECT_THROW(results::write_learned_model(dir / "no" / "m.json", sample_model(false)), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir / "no"));
}

}  // namespace
}  // namespace odotune::results
