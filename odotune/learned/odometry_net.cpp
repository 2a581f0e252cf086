#include <odotune/learned/odometry_net.h>

#include <stdexcept>
#include <type_traits>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace odotune::learned {

OdometryNet OdometryNet::with_units(int units, int window) {
  OdometryNet out;
  switch (units) {
    case 3: out.net_ = Net3{}; break;
    case 5: out.net_ = Net5{}; break;
    case 8: out.net_ = Net8{}; break;
    default:
      throw std::invalid_argument(fmt::format("a velocity net of {} units; expected {}", units,
                                              fmt::join(kOdometryNetUnits, ", ")));
  }
  std::visit([window](auto& n) { n.window = window; }, out.net_);
  return out;
}

int OdometryNet::units() const {
  return std::visit([](const auto& n) { return std::decay_t<decltype(n)>::kHidden; }, net_);
}

int OdometryNet::window() const {
  return std::visit([](const auto& n) { return n.window; }, net_);
}

int OdometryNet::weight_count() const {
  return std::visit([](const auto& n) { return std::decay_t<decltype(n)>::kWeights; }, net_);
}

const double* OdometryNet::weights() const {
  return std::visit([](const auto& n) { return n.weights.data(); }, net_);
}

OutputActivation OdometryNet::activation() const {
  return std::visit([](const auto& n) { return n.activation; }, net_);
}

bool OdometryNet::IsValid(std::string* why) const {
  return std::visit([why](const auto& n) { return n.IsValid(why); }, net_);
}

bool OdometryNet::operator==(const OdometryNet& other) const {
  if (net_.index() != other.net_.index()) return false;
  return std::visit(
      [&other](const auto& a) {
        const auto& b = std::get<std::decay_t<decltype(a)>>(other.net_);
        return a.weights == b.weights && a.input_mean == b.input_mean && a.input_sd == b.input_sd &&
               a.output_mean == b.output_mean && a.output_sd == b.output_sd && a.activation == b.activation &&
               a.window == b.window;
      },
      net_);
}

double OdometryNet::predict(const double* raw_window) const {
  return std::visit([raw_window](const auto& n) { return n.predict(raw_window); }, net_);
}

void OdometryNet::zero_output() {
  std::visit(
      [](auto& n) {
        using L = LstmLayout<kInputs, std::decay_t<decltype(n)>::kHidden>;
        n.output_mean = 0.0;
        for (int j = L::kDense; j <= L::kDenseBias; ++j) n.weights[static_cast<std::size_t>(j)] = 0.0;
      },
      net_);
}

LstmTrainingSummary OdometryNet::train(const SequenceSet& train_set, const SequenceSet& validation,
                                       const LstmTrainingOptions& options) {
  return std::visit([&](auto& n) { return train_lstm(n, train_set, validation, options); }, net_);
}

LstmTrainingSummary OdometryNet::retrain(const SequenceSet& train_set, const LstmTrainingOptions& options) {
  return std::visit([&](auto& n) { return retrain_lstm(n, train_set, options); }, net_);
}

double OdometryNet::mae(const SequenceSet& set) const {
  return std::visit([&set](const auto& n) { return lstm_mae(n, set); }, net_);
}

}  // namespace odotune::learned
