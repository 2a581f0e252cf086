#include <odotune/results/lstm_json.h>

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace odotune::results {

namespace {

[[noreturn]] void bad_lstm(const std::string& field, const std::string& what) {
  throw std::invalid_argument(fmt::format("LSTM JSON: field '{}': {}", field, what));
}

const nlohmann::json& field(const nlohmann::json& j, const char* name) {
  const auto it = j.find(name);
  if (it == j.end()) bad_lstm(name, "missing");
  return *it;
}

double finite_number(const nlohmann::json& v, const std::string& name) {
  if (!v.is_number()) bad_lstm(name, fmt::format("expected a number, got {}", v.dump()));
  const double x = v.get<double>();
  if (!std::isfinite(x)) bad_lstm(name, "expected a finite number");
  return x;
}

int integer(const nlohmann::json& v, const std::string& name) {
  if (!v.is_number_integer()) bad_lstm(name, fmt::format("expected an integer, got {}", v.dump()));
  return v.get<int>();
}

// Reads a numeric array of exactly n finite numbers into out[0..n).
void numbers(const nlohmann::json& j, const char* name, int n, double* out) {
  const nlohmann::json& v = field(j, name);
  if (!v.is_array()) bad_lstm(name, fmt::format("expected an array of {} numbers", n));
  if (v.size() != static_cast<std::size_t>(n))
    bad_lstm(name, fmt::format("expected {} numbers, got {}", n, v.size()));
  for (int k = 0; k < n; ++k)
    out[k] = finite_number(v[static_cast<std::size_t>(k)], fmt::format("{}[{}]", name, k));
}

}  // namespace

template <int I, int H>
nlohmann::json lstm_to_json(const learned::LstmNet<I, H>& net) {
  std::string why;
  if (!net.IsValid(&why)) throw std::invalid_argument("LSTM JSON: cannot write an invalid net: " + why);
  nlohmann::json j;
  j["format"] = kLstmJsonFormat;
  j["inputs"] = I;
  j["hidden"] = H;
  j["activation"] = net.activation == learned::OutputActivation::relu ? "relu" : "linear";
  j["window"] = net.window;
  j["input_mean"] = net.input_mean;
  j["input_sd"] = net.input_sd;
  j["output_mean"] = net.output_mean;
  j["output_sd"] = net.output_sd;
  j["weights"] = net.weights;
  return j;
}

template <int I, int H>
learned::LstmNet<I, H> lstm_from_json(const nlohmann::json& j) {
  if (!j.is_object()) throw std::invalid_argument("LSTM JSON: expected an object at the top level");
  const nlohmann::json& format = field(j, "format");
  if (!format.is_string() || format.get<std::string>() != kLstmJsonFormat)
    bad_lstm("format", fmt::format("expected \"{}\", got {}", kLstmJsonFormat, format.dump()));
  if (const int inputs = integer(field(j, "inputs"), "inputs"); inputs != I)
    bad_lstm("inputs", fmt::format("expected {} (this net's input count), got {}", I, inputs));
  if (const int hidden = integer(field(j, "hidden"), "hidden"); hidden != H)
    bad_lstm("hidden", fmt::format("expected {} (this net's unit count), got {}", H, hidden));

  learned::LstmNet<I, H> net;
  const nlohmann::json& act = field(j, "activation");
  if (act == "linear") {
    net.activation = learned::OutputActivation::linear;
  } else if (act == "relu") {
    net.activation = learned::OutputActivation::relu;
  } else {
    bad_lstm("activation", fmt::format(R"(expected "linear" or "relu", got {})", act.dump()));
  }
  net.window = integer(field(j, "window"), "window");
  if (net.window < 1 || net.window > net.kMaxWindow)
    bad_lstm("window", fmt::format("expected 1..{}, got {}", net.kMaxWindow, net.window));

  numbers(j, "input_mean", I, net.input_mean.data());
  numbers(j, "input_sd", I, net.input_sd.data());
  for (int k = 0; k < I; ++k)
    if (!(net.input_sd[k] > 0.0))
      bad_lstm(fmt::format("input_sd[{}]", k), fmt::format("expected > 0, got {}", net.input_sd[k]));
  net.output_mean = finite_number(field(j, "output_mean"), "output_mean");
  net.output_sd = finite_number(field(j, "output_sd"), "output_sd");
  if (!(net.output_sd > 0.0)) bad_lstm("output_sd", fmt::format("expected > 0, got {}", net.output_sd));
  numbers(j, "weights", net.kWeights, net.weights.data());
  return net;
}

#define ODOTUNE_INSTANTIATE_LSTM_JSON(I, H)                                  \
  template nlohmann::json lstm_to_json<I, H>(const learned::LstmNet<I, H>&); \
  template learned::LstmNet<I, H> lstm_from_json<I, H>(const nlohmann::json&);

ODOTUNE_INSTANTIATE_LSTM_JSON(3, 3)
ODOTUNE_INSTANTIATE_LSTM_JSON(3, 5)
ODOTUNE_INSTANTIATE_LSTM_JSON(3, 8)
ODOTUNE_INSTANTIATE_LSTM_JSON(5, 10)

#undef ODOTUNE_INSTANTIATE_LSTM_JSON

nlohmann::json odometry_net_to_json(const learned::OdometryNet& net) {
  return net.visit([](const auto& n) { return lstm_to_json(n); });
}

learned::OdometryNet odometry_net_from_json(const nlohmann::json& j) {
  if (!j.is_object()) throw std::invalid_argument("LSTM JSON: expected an object at the top level");
  const int hidden = integer(field(j, "hidden"), "hidden");
  switch (hidden) {
    case 3: return lstm_from_json<learned::OdometryNet::kInputs, 3>(j);
    case 5: return lstm_from_json<learned::OdometryNet::kInputs, 5>(j);
    case 8: return lstm_from_json<learned::OdometryNet::kInputs, 8>(j);
    default:
      bad_lstm("hidden", fmt::format("expected one of the velocity nets' unit counts 3, 5, 8, got {}", hidden));
  }
}

}  // namespace odotune::results
