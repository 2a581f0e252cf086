// LSTM forward pass (odotune/learned/lstm.h) against an independent Eigen matrix
// formulation of Fariña et al. (Sensors 2023) eqs. 5–8, the ReLU floor,
// predict's standardisation / de-normalisation, the zero-weight net and IsValid.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <odotune/core/counter_rng.h>
#include <odotune/learned/lstm.h>

namespace odotune::filters {
namespace {

// Uniform in [lo, hi), seeded, independent of the code under test's init.
double draw(std::uint64_t seed, std::uint64_t n, double lo, double hi) {
  return lo + (hi - lo) * core::counter_uniform01(seed, 7, n, 0, 99);
}

template <int I, int H>
learned::LstmNet<I, H> random_net(std::uint64_t seed, double scale) {
  learned::LstmNet<I, H> net;
  for (int n = 0; n < net.kWeights; ++n)
    net.weights[n] = draw(seed, static_cast<std::uint64_t>(n), -scale, scale);
  return net;
}

std::vector<double> random_window(std::uint64_t seed, int window, int inputs, double scale) {
  std::vector<double> x(static_cast<std::size_t>(window * inputs));
  for (std::size_t n = 0; n < x.size(); ++n) x[n] = draw(seed + 1000, n, -scale, scale);
  return x;
}

// Reference LSTM written as matrices: the weight vector is read by *shape*
// (Keras' kernel (I, 4H), recurrent kernel (H, 4H), bias (4H), dense (H), bias),
// gates split as column blocks i, f, c, o.
template <int I, int H>
double reference_lstm(const std::array<double, learned::LstmLayout<I, H>::kCount>& w,
                      const std::vector<double>& x, int window, bool relu) {
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const Eigen::Map<const RowMajor> W(w.data(), I, 4 * H);
  const Eigen::Map<const RowMajor> U(w.data() + I * 4 * H, H, 4 * H);
  const Eigen::Map<const Eigen::RowVectorXd> b(w.data() + (I + H) * 4 * H, 4 * H);
  const Eigen::Map<const Eigen::RowVectorXd> d(w.data() + (I + H + 1) * 4 * H, H);
  const double d0 = w[(I + H + 1) * 4 * H + H];
  auto sigma = [](const Eigen::RowVectorXd& v) {
    return Eigen::RowVectorXd((1.0 + (-v.array()).exp()).inverse());
  };
  Eigen::RowVectorXd h = Eigen::RowVectorXd::Zero(H), c = Eigen::RowVectorXd::Zero(H);
  for (int t = 0; t < window; ++t) {
    const Eigen::Map<const Eigen::RowVectorXd> xt(x.data() + t * I, I);
    const Eigen::RowVectorXd z = xt * W + h * U + b;
    const Eigen::RowVectorXd ig = sigma(z.segment(0, H));
    const Eigen::RowVectorXd fg = sigma(z.segment(H, H));
    const Eigen::RowVectorXd gc = z.segment(2 * H, H).array().tanh();
    const Eigen::RowVectorXd og = sigma(z.segment(3 * H, H));
    c = (fg.array() * c.array() + ig.array() * gc.array()).matrix();
    h = (og.array() * c.array().tanh()).matrix();
  }
  const double out = d.dot(h) + d0;
  return relu ? std::max(0.0, out) : out;
}

TEST(LstmLayout, CountsAndOffsets) {
  EXPECT_EQ((learned::LstmLayout<3, 5>::kCount), 186);
  EXPECT_EQ((learned::LstmLayout<5, 10>::kCount), 651);
  EXPECT_EQ((learned::LstmLayout<3, 5>::kRecurrent), 3 * 20);
  EXPECT_EQ((learned::LstmLayout<3, 5>::kBias), 3 * 20 + 5 * 20);
  EXPECT_EQ((learned::LstmLayout<3, 5>::kDense), 3 * 20 + 5 * 20 + 20);
  EXPECT_EQ((learned::LstmLayout<3, 5>::kDenseBias), 185);
}

template <int I, int H>
void check_against_reference(std::uint64_t seed) {
  const auto net = random_net<I, H>(seed, 0.8);
  for (int window : {1, 2, 20}) {
    const auto x = random_window(seed, window, I, 2.0);
    const double ours = learned::lstm_forward<I, H, double>(net.weights.data(), x.data(), window,
                                                            learned::OutputActivation::linear);
    const double ref = reference_lstm<I, H>(net.weights, x, window, false);
    EXPECT_NEAR(ours, ref, 1e-12 * (1.0 + std::abs(ref))) << "window " << window << " seed " << seed;
  }
}

TEST(LstmForward, MatchesMatrixReference) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    check_against_reference<3, 5>(seed);
    check_against_reference<5, 10>(seed);
    check_against_reference<2, 3>(seed);
  }
}

TEST(LstmForward, OutputDependsOnOldSamples) {
  // Memory: changing the oldest sample of a 20-window changes the output.
  const auto net = random_net<3, 5>(11, 0.8);
  auto x = random_window(11, 20, 3, 1.0);
  const double a = learned::lstm_forward<3, 5, double>(net.weights.data(), x.data(), 20,
                                                       learned::OutputActivation::linear);
  x[0] += 1.0;
  const double b = learned::lstm_forward<3, 5, double>(net.weights.data(), x.data(), 20,
                                                       learned::OutputActivation::linear);
  EXPECT_NE(a, b);
}

TEST(LstmForward, ReluFloorsAtZeroAndPassesPositive) {
  auto net = random_net<5, 10>(3, 0.5);
  const auto x = random_window(3, 20, 5, 1.0);
  const double base = learned::lstm_forward<5, 10, double>(net.weights.data(), x.data(), 20,
                                                           learned::OutputActivation::linear);
  // Shift the dense bias so that the linear output is −0.7, then +0.7.
  const int bias = learned::LstmLayout<5, 10>::kDenseBias;
  net.weights[bias] += -0.7 - base;
  const double neg_lin = learned::lstm_forward<5, 10, double>(net.weights.data(), x.data(), 20,
                                                              learned::OutputActivation::linear);
  EXPECT_NEAR(neg_lin, -0.7, 1e-12);
  EXPECT_EQ(
      (learned::lstm_forward<5, 10, double>(net.weights.data(), x.data(), 20, learned::OutputActivation::relu)),
      0.0);
  net.weights[bias] += 1.4;
  const double pos = learned::lstm_forward<5, 10, double>(net.weights.data(), x.data(), 20,
                                                          learned::OutputActivation::relu);
  EXPECT_NEAR(pos, 0.7, 1e-12);
  EXPECT_NEAR(pos, (reference_lstm<5, 10>(net.weights, x, 20, true)), 1e-12);
}

TEST(LstmForward, ZeroWeightsGiveOutputBias) {
  learned::LstmNet<3, 5> net;
  net.weights[learned::LstmLayout<3, 5>::kDenseBias] = 0.37;
  const auto x = random_window(5, 20, 3, 3.0);
  EXPECT_EQ((learned::lstm_forward<3, 5, double>(net.weights.data(), x.data(), 20,
                                                 learned::OutputActivation::linear)),
            0.37);
  // Zero weights: every gate is σ(0) = 1/2, the candidate tanh(0) = 0, so c = h = 0.
  net.output_mean = 2.0;
  net.output_sd = 3.0;
  EXPECT_DOUBLE_EQ(net.predict(x.data()), 2.0 + 3.0 * 0.37);
}

TEST(LstmNetPredict, StandardisesInputsAndDenormalisesOutput) {
  auto net = random_net<3, 5>(21, 0.8);
  net.window = 20;
  net.input_mean = {10.0, -4.0, 0.5};
  net.input_sd = {2.0, 0.25, 4.0};
  net.output_mean = 1.5;
  net.output_sd = 0.2;
  const auto z = random_window(21, 20, 3, 1.5);  // standardised window
  std::vector<double> raw(z.size());
  for (int t = 0; t < 20; ++t)
    for (int k = 0; k < 3; ++k) raw[t * 3 + k] = net.input_mean[k] + net.input_sd[k] * z[t * 3 + k];
  const double expected = 1.5 + 0.2 * reference_lstm<3, 5>(net.weights, z, 20, false);
  EXPECT_NEAR(net.predict(raw.data()), expected, 1e-12);

  std::vector<double> back(raw.size());
  net.standardise(raw.data(), back.data());
  for (std::size_t n = 0; n < z.size(); ++n) EXPECT_NEAR(back[n], z[n], 1e-12);

  // The ReLU's zero maps to output_mean (the floor).
  net.activation = learned::OutputActivation::relu;
  net.weights[learned::LstmLayout<3, 5>::kDenseBias] -= 1e3;
  EXPECT_EQ(net.predict(raw.data()), 1.5);
}

TEST(LstmNetIsValid, NamesTheBadValue) {
  std::string why;
  learned::LstmNet<3, 5> net;
  EXPECT_TRUE(net.IsValid(&why)) << why;
  auto bad = net;
  bad.window = 0;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("window"), std::string::npos) << why;
  bad = net;
  bad.weights[17] = std::nan("");
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("weights[17]"), std::string::npos) << why;
  bad = net;
  bad.input_sd[2] = 0.0;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("input_sd[2]"), std::string::npos) << why;
  bad = net;
  bad.output_sd = -1.0;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("output_sd"), std::string::npos) << why;
  bad = net;
  bad.input_mean[0] = INFINITY;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("input_mean[0]"), std::string::npos) << why;
}

}  // namespace
}  // namespace odotune::filters
