// One velocity net of the learned odometry (odotune/learned/learned_odometry.h):
// three inputs per step and one of the unit counts training can choose
// (kOdometryNetUnits; the paper's is 5, §4), behind one value type so that
// the model, its training, retraining and its file do not depend on the size.
// Each size is an LstmNet<3, H> (odotune/learned/lstm.h) with its own compiled
// kernels; the choice among them is odotune/learned/odometry_selection.h's.
#pragma once

#include <array>
#include <string>
#include <variant>

#include <odotune/learned/lstm.h>
#include <odotune/learned/lstm_training.h>

namespace odotune::learned {

// The unit counts an OdometryNet can have. Above 8 a Levenberg–Marquardt
// step (the normal equations of ~4H(H + 4) weights over every window)
// costs too much for cross-validated training on a laptop.
inline constexpr std::array<int, 3> kOdometryNetUnits = {3, 5, 8};

class OdometryNet {
 public:
  static constexpr int kInputs = 3;
  using Net3 = LstmNet<kInputs, 3>;
  using Net5 = LstmNet<kInputs, 5>;
  using Net8 = LstmNet<kInputs, 8>;

  OdometryNet() : net_(Net5{}) {}  // the paper's 5 units
  template <int H>
  OdometryNet(const LstmNet<kInputs, H>& net)
      : net_(net) {}  // NOLINT(google-explicit-constructor): a net is one
  // A fresh net of `units` (one of kOdometryNetUnits) and `window` steps;
  // throws std::invalid_argument (one line) for another count.
  static OdometryNet with_units(int units, int window);

  int units() const;
  int window() const;
  int weight_count() const;
  const double* weights() const;
  OutputActivation activation() const;
  bool IsValid(std::string* why) const;
  bool operator==(const OdometryNet& other) const;

  // LstmNet::predict: raw_window is window() × kInputs raw samples.
  double predict(const double* raw_window) const;
  // The dense output's weights and bias and output_mean set to 0: the net
  // outputs exactly 0 (a correction that leaves its base unchanged).
  void zero_output();

  // train_lstm, retrain_lstm and lstm_mae (odotune/learned/lstm_training.h) on this net.
  LstmTrainingSummary train(const SequenceSet& train, const SequenceSet& validation,
                            const LstmTrainingOptions& options);
  LstmTrainingSummary retrain(const SequenceSet& train, const LstmTrainingOptions& options);
  double mae(const SequenceSet& set) const;

  // The net itself, for its file (odotune/results/lstm_json.h).
  template <class F>
  decltype(auto) visit(F&& f) const {
    return std::visit(std::forward<F>(f), net_);
  }

 private:
  std::variant<Net3, Net5, Net8> net_;
};

}  // namespace odotune::learned
