// Calibration input (odotune/calibration/calibration_input.h): the truth schedule
// from sim.effects, odometry rows and calibration samples of a simulated
// wheelchair track against the simulated truth, external velocities derived
// from the ground truth, ground truth interpolated to odometry rows, and the
// one-line errors for unusable tracks. Also the pose-series helpers
// (pose_series.h) the derivation uses.
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/calibration/calibration_input.h>
#include <odotune/objectives/pose_series.h>

#include "support/calibration_track.h"

namespace odotune::calibration {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using testing_support::chair_track;
using testing_support::ChairTrackOptions;

constexpr double kPi = std::numbers::pi;

tracks::TrackMeta chair_meta(const std::string& effects) {
  tracks::TrackMeta m;
  m.name = "meta_only";
  m.wheel_radius_left_m = 0.32;
  m.wheel_radius_right_m = 0.30;
  m.wheel_base_m = 0.65;
  m.extra.emplace_back("sim.seed", "3");
  m.extra.emplace_back("sim.effects", effects);
  return m;
}

// The simulated wheelchair track most tests here share (60 s, 1 % / 1.2 %
// radius errors, 2 % wheel-base error, ext σ 0.03 so that its variance
// column differs from the default variances).
const tracks::Track& shared_track() {
  static const tracks::Track track = [] {
    ChairTrackOptions o;
    o.duration_s = 60.0;
    o.effects = {"radius_error:scale_l=0.99,scale_r=1.012", "wheel_base_error:scale=1.02"};
    o.ext_sigma_v_m_s = 0.03;
    o.ext_sigma_w_rad_s = 0.03;
    return chair_track(o);
  }();
  return track;
}

TEST(CalibrationTruth, ScheduleFromSimEffects) {
  const auto truth = truth_from_metadata(
      chair_meta("radius_error:scale_l=0.99,scale_r=1.01; wheel_base_error:scale=1.02; lateral_skid:k=0.01; "
                 "radius_step:t=30,scale_l=1.05,scale_r=0.98"));
  ASSERT_TRUE(truth.has_value());
  ASSERT_EQ(truth->params.size(), 2u);
  ASSERT_EQ(truth->change_times(), std::vector<double>{30.0});
  const auto& before = truth->at(29.999);
  EXPECT_NEAR(before.wheel_radius_left_m, 0.32 * 0.99, 1e-15);
  EXPECT_NEAR(before.wheel_radius_right_m, 0.30 * 1.01, 1e-15);
  EXPECT_NEAR(before.wheel_base_m, 0.65 * 1.02, 1e-15);
  EXPECT_EQ(&truth->at(-1e9), &before);
  // The step holds from t on (t included), as in the simulator.
  const auto& after = truth->at(30.0);
  EXPECT_NEAR(after.wheel_radius_left_m, 0.32 * 0.99 * 1.05, 1e-15);
  EXPECT_NEAR(after.wheel_radius_right_m, 0.30 * 1.01 * 0.98, 1e-15);
  EXPECT_NEAR(after.wheel_base_m, 0.65 * 1.02, 1e-15);
  EXPECT_EQ(&truth->at(1e9), &after);
}

TEST(CalibrationTruth, NoneNominalMissingAndMalformed) {
  const auto none = truth_from_metadata(chair_meta("none"));
  ASSERT_TRUE(none.has_value());
  ASSERT_EQ(none->params.size(), 1u);
  EXPECT_TRUE(none->change_times().empty());
  EXPECT_DOUBLE_EQ(none->at(5.0).wheel_radius_right_m, 0.30);
  EXPECT_DOUBLE_EQ(none->at(5.0).wheel_base_m, 0.65);

  tracks::TrackMeta recorded = chair_meta("none");
  recorded.extra.clear();
  EXPECT_FALSE(truth_from_metadata(recorded).has_value());
  tracks::TrackMeta no_base = chair_meta("radius_error:scale_l=0.99");
  no_base.wheel_base_m.reset();
  EXPECT_FALSE(truth_from_metadata(no_base).has_value());

  try {
    truth_from_metadata(chair_meta("radius_eror:scale_l=0.99"));
    FAIL() << "a misspelt effect must throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("meta_only"), HasSubstr("radius_eror")));
  }
  EXPECT_THROW(truth_from_metadata(chair_meta("radius_error:scale_l=0.99;; gyro_bias:b=0.1")),
               std::invalid_argument);
}

TEST(CalibrationInputOptions, Validation) {
  std::string why;
  CalibrationInputOptions o;
  EXPECT_TRUE(o.IsValid(&why));
  o.ext_from_gt_rate_hz = -1.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_THAT(why, HasSubstr("ext_from_gt_rate_hz"));
  o = {};
  o.default_w_var = 0.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_THAT(why, HasSubstr("default_w_var"));
  o = {};
  o.default_v_var = std::nan("");
  EXPECT_FALSE(o.IsValid(&why));
}

TEST(CalibrationInput, RowsAndSamplesMatchTheSimulatedTruth) {
  const tracks::Track& track = shared_track();
  const CalibrationInput in = build_calibration_input(track, {});
  EXPECT_EQ(in.track_name, track.name());
  EXPECT_DOUBLE_EQ(in.nominal.wheel_radius_left_m, 0.32);
  EXPECT_DOUBLE_EQ(in.nominal.wheel_base_m, 0.65);
  ASSERT_TRUE(in.truth.has_value());
  const filters::OdometryParams truth = testing_support::chair_truth(0.99, 1.012, 1.02);
  EXPECT_NEAR(in.truth->at(10.0).wheel_radius_right_m, truth.wheel_radius_right_m, 1e-12);

  // Every track row has ticks (encoders and GT at 100 Hz, ext at 10 Hz).
  ASSERT_EQ(in.t.size(), track.size());
  EXPECT_EQ(in.omega_l[0], 0.0);
  ASSERT_TRUE(in.has_gt);
  for (std::size_t r = 0; r < in.t.size(); r += 97) {
    EXPECT_EQ(in.gt_x[r], track.col(tracks::Col::gt_x)[r]);
    EXPECT_EQ(in.gt_theta[r], track.col(tracks::Col::gt_theta)[r]);
  }
  // Rates from ticks: Δticks·2π/8800/Δt over each row.
  const std::size_t r = in.t.size() / 2;
  const double expected_wr = static_cast<double>(track.ticks_r()[r] - track.ticks_r()[r - 1]) * 2.0 * kPi /
                             8800.0 / (track.t()[r] - track.t()[r - 1]);
  EXPECT_NEAR(in.omega_r[r], expected_wr, 1e-9);

  // One sample per ext row except the one at t = 0 (no rate before it).
  std::size_t ext_rows = 0;
  for (std::size_t i = 0; i < track.size(); ++i) ext_rows += track.at(tracks::Col::v_ext, i) ? 1 : 0;
  ASSERT_EQ(in.samples.size(), ext_rows - 1);
  ASSERT_EQ(in.sample_row.size(), in.samples.size());
  ASSERT_EQ(in.sample_t.size(), in.samples.size());
  EXPECT_EQ(in.samples[0].dt_s, 0.0);
  EXPECT_NEAR(in.sample_t[0], 0.1, 1e-12);
  double sum_dv = 0, sum_dw = 0, ss_dv = 0, ss_dw = 0;
  for (std::size_t i = 0; i < in.samples.size(); ++i) {
    const auto& s = in.samples[i];
    EXPECT_EQ(in.t[in.sample_row[i]], in.sample_t[i]);  // same rows in the simulation
    if (i > 0) {
      EXPECT_NEAR(s.dt_s, 0.1, 1e-9);
    }
    EXPECT_NEAR(s.v_var, 9e-4, 1e-15);  // the column, not the default
    EXPECT_NEAR(s.w_var, 9e-4, 1e-15);
    {  // The rate is the mean over the 0.1 s window centred on the sample.
      const std::size_t row = in.sample_row[i];
      const std::size_t a = row >= 5 ? row - 5 : 0, b = std::min(row + 5, in.t.size() - 1);
      double angle = 0.0;
      for (std::size_t k = a + 1; k <= b; ++k) angle += in.omega_l[k] * (in.t[k] - in.t[k - 1]);
      EXPECT_NEAR(s.omega_l_rad_s, angle / (in.t[b] - in.t[a]), 1e-9);
    }
    // Odometry with the TRUE parameters reproduces the external velocity.
    const auto odo = filters::body_velocity(truth, s.omega_l_rad_s, s.omega_r_rad_s);
    sum_dv += odo.v_m_s - s.v_m_s;
    sum_dw += odo.w_rad_s - s.w_rad_s;
    ss_dv += (odo.v_m_s - s.v_m_s) * (odo.v_m_s - s.v_m_s);
    ss_dw += (odo.w_rad_s - s.w_rad_s) * (odo.w_rad_s - s.w_rad_s);
  }
  const double n = static_cast<double>(in.samples.size());
  EXPECT_LT(std::abs(sum_dv / n), 0.004);
  EXPECT_LT(std::abs(sum_dw / n), 0.006);
  // σ_ext = 0.03 plus encoder quantisation over 10 ms.
  EXPECT_LT(std::sqrt(ss_dv / n), 0.045);
  EXPECT_LT(std::sqrt(ss_dw / n), 0.06);
  EXPECT_GT(std::sqrt(ss_dv / n), 0.02);  // the noise is really there
}

TEST(CalibrationInput, ExtFromGroundTruthReproducesTheExternalSensor) {
  // A noise-free external sensor: the GT-derived velocities must match it up
  // to the central difference's error at acceleration changes.
  ChairTrackOptions o;
  o.duration_s = 40.0;
  o.ext_sigma_v_m_s = 0.0;
  o.ext_sigma_w_rad_s = 0.0;
  const tracks::Track track = chair_track(o);
  CalibrationInputOptions opt;
  opt.ext_from_gt_rate_hz = 10.0;
  opt.estimate_ext_noise = false;  // the given variances
  opt.default_v_var = 1e-4;
  opt.default_w_var = 2e-4;
  const CalibrationInput derived = build_calibration_input(track, opt);
  EXPECT_THAT(derived.ext_noise, HasSubstr("as given"));
  const CalibrationInput measured = build_calibration_input(track, {});
  // Measured: σ = 0 gives a zero variance column, so the defaults are used.
  EXPECT_DOUBLE_EQ(measured.samples[0].v_var, CalibrationInputOptions{}.default_v_var);

  // Windows ±0.05 s inside the GT: every t_k = k/10 from 0.1 s to the last.
  ASSERT_GT(derived.samples.size(), 350u);
  EXPECT_NEAR(derived.sample_t.front(), 0.1, 1e-12);
  // The last measurement lies within half a period of the GT's end.
  ASSERT_LE(derived.samples.size(), measured.samples.size());
  ASSERT_GE(derived.samples.size() + 1, measured.samples.size());
  double ss_v = 0, ss_w = 0, max_v = 0;
  for (std::size_t i = 0; i < derived.samples.size(); ++i) {
    ASSERT_NEAR(derived.sample_t[i], measured.sample_t[i], 1e-9);
    EXPECT_EQ(derived.samples[i].v_var, 1e-4);
    EXPECT_EQ(derived.samples[i].w_var, 2e-4);
    EXPECT_EQ(derived.samples[i].omega_r_rad_s, measured.samples[i].omega_r_rad_s);
    const double dv = derived.samples[i].v_m_s - measured.samples[i].v_m_s;
    const double dw = derived.samples[i].w_rad_s - measured.samples[i].w_rad_s;
    ss_v += dv * dv;
    ss_w += dw * dw;
    max_v = std::max(max_v, std::abs(dv));
  }
  const double n = static_cast<double>(derived.samples.size());
  EXPECT_LT(std::sqrt(ss_v / n), 0.005);
  EXPECT_LT(std::sqrt(ss_w / n), 0.02);
  EXPECT_LT(max_v, 0.03);
}

TEST(CalibrationInput, OmegaColumnsAndGroundTruthOnOtherRows) {
  // Hand-made: omega on even rows (every 0.1 s), GT on odd rows (0.05 s
  // later), x = 0.5 t, y = 0.1 t, θ = 0.2 t; ext on every fourth row.
  tracks::TrackData d;
  d.meta.name = "handmade";
  d.meta.wheel_radius_left_m = 0.1;
  d.meta.wheel_radius_right_m = 0.1;
  d.meta.wheel_base_m = 0.5;
  const std::size_t n = 40;
  for (tracks::Col c : {tracks::Col::omega_l, tracks::Col::omega_r, tracks::Col::gt_x, tracks::Col::gt_y,
                        tracks::Col::gt_theta, tracks::Col::v_ext, tracks::Col::w_ext})
    d.ensure(c);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = 0.05 * static_cast<double>(i);
    d.t.push_back(t);
    for (auto* c : {&d.col(tracks::Col::omega_l), &d.col(tracks::Col::omega_r), &d.col(tracks::Col::gt_x),
                    &d.col(tracks::Col::gt_y), &d.col(tracks::Col::gt_theta), &d.col(tracks::Col::v_ext),
                    &d.col(tracks::Col::w_ext)})
      c->push_back(std::nan(""));
    if (i % 2 == 0) {
      d.col(tracks::Col::omega_l).back() = 4.0 + t;
      d.col(tracks::Col::omega_r).back() = 5.0 - t;
    } else {
      d.col(tracks::Col::gt_x).back() = 0.5 * t;
      d.col(tracks::Col::gt_y).back() = 0.1 * t;
      d.col(tracks::Col::gt_theta).back() = 0.2 * t;
    }
    if (i % 4 == 1) {  // between two omega rows
      d.col(tracks::Col::v_ext).back() = 0.45;
      d.col(tracks::Col::w_ext).back() = 0.2;
    }
  }
  const tracks::Track track(std::move(d));
  const CalibrationInput in = build_calibration_input(track, {});
  ASSERT_EQ(in.t.size(), n / 2);
  EXPECT_EQ(in.omega_l[0], 4.0);  // omega rows keep their own sample, row 0 included
  EXPECT_DOUBLE_EQ(in.omega_r[3], 5.0 - 0.3);
  // GT interpolated to the omega rows; NaN before the first GT sample.
  EXPECT_TRUE(std::isnan(in.gt_x[0]));
  for (std::size_t r = 1; r < in.t.size(); ++r) {
    EXPECT_NEAR(in.gt_x[r], 0.5 * in.t[r], 1e-12);
    EXPECT_NEAR(in.gt_y[r], 0.1 * in.t[r], 1e-12);
    EXPECT_NEAR(in.gt_theta[r], 0.2 * in.t[r], 1e-12);
  }
  // Samples at 0.05, 0.25, ...: the omega row just before (0.0, 0.2, ...).
  ASSERT_EQ(in.samples.size(), n / 4);
  for (std::size_t i = 0; i < in.samples.size(); ++i) {
    EXPECT_NEAR(in.sample_t[i], 0.05 + 0.2 * static_cast<double>(i), 1e-12);
    EXPECT_EQ(in.sample_row[i], 2 * i);
    // The mean over the 0.1 s window around the sample: ω_l = 4 + t is
    // linear, so it is its value at the sample's time.
    EXPECT_NEAR(in.samples[i].omega_l_rad_s, 4.0 + in.sample_t[i], 1e-12);
    EXPECT_DOUBLE_EQ(in.samples[i].v_var, CalibrationInputOptions{}.default_v_var);
  }
  // Without the window: the omega row just before the sample.
  CalibrationInputOptions single;
  single.wheel_rate_window_s = 0.0;
  const CalibrationInput raw = build_calibration_input(track, single);
  ASSERT_EQ(raw.samples.size(), n / 4);
  for (std::size_t i = 0; i < raw.samples.size(); ++i)
    EXPECT_DOUBLE_EQ(raw.samples[i].omega_l_rad_s, 4.0 + raw.t[2 * i]);
}

TEST(CalibrationInput, UnwrapsAWrappedGroundTruthHeading) {
  // A spin in place whose GT heading is wrapped to (−π, π].
  tracks::TrackData d;
  d.meta.name = "spin";
  d.meta.wheel_radius_left_m = d.meta.wheel_radius_right_m = 0.1;
  d.meta.wheel_base_m = 0.5;
  for (tracks::Col c : {tracks::Col::omega_l, tracks::Col::omega_r, tracks::Col::gt_x, tracks::Col::gt_y,
                        tracks::Col::gt_theta})
    d.ensure(c);
  for (int i = 0; i < 200; ++i) {
    const double t = 0.01 * i;
    d.t.push_back(t);
    d.col(tracks::Col::omega_l).push_back(-10.0);
    d.col(tracks::Col::omega_r).push_back(10.0);
    d.col(tracks::Col::gt_x).push_back(0.0);
    d.col(tracks::Col::gt_y).push_back(0.0);
    d.col(tracks::Col::gt_theta).push_back(core::wrap_angle(4.0 * t));
  }
  const tracks::Track track(std::move(d));
  CalibrationInputOptions o;
  o.ext_from_gt_rate_hz = 20.0;
  const CalibrationInput in = build_calibration_input(track, o);
  EXPECT_NEAR(in.gt_theta.back(), 4.0 * 1.99, 1e-9);
  for (const auto& s : in.samples) EXPECT_NEAR(s.w_rad_s, 4.0, 1e-9);
}

TEST(CalibrationInput, BadTracksGiveOneLineNamingTheTrack) {
  auto message = [](const tracks::Track& track, const CalibrationInputOptions& o) -> std::string {
    try {
      build_calibration_input(track, o);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no exception)";
  };
  ChairTrackOptions no_ext_no_gt;
  no_ext_no_gt.duration_s = 5.0;
  no_ext_no_gt.ext = false;
  no_ext_no_gt.gt = false;
  const tracks::Track bare = chair_track(no_ext_no_gt);
  const std::string m1 = message(bare, {});
  EXPECT_THAT(m1, AllOf(HasSubstr("'chair'"), HasSubstr("v_ext"), HasSubstr("ground truth")));
  EXPECT_EQ(m1.find('\n'), std::string::npos);
  CalibrationInputOptions derive;
  derive.ext_from_gt_rate_hz = 10.0;
  EXPECT_THAT(message(bare, derive), AllOf(HasSubstr("'chair'"), HasSubstr("ground truth")));

  ChairTrackOptions no_ext;
  no_ext.duration_s = 5.0;
  no_ext.ext = false;
  const tracks::Track gt_only = chair_track(no_ext);
  EXPECT_THAT(message(gt_only, {}), AllOf(HasSubstr("'chair'"), HasSubstr("ext_from_gt_rate_hz")));
  EXPECT_NO_THROW(build_calibration_input(gt_only, derive));

  tracks::TrackData d = shared_track().data();
  d.meta.name = "anonymous_robot";
  d.meta.wheel_radius_left_m.reset();
  EXPECT_THAT(message(tracks::Track(d), {}),
              AllOf(HasSubstr("'anonymous_robot'"), HasSubstr("robot.wheel_radius_left")));
  d = shared_track().data();
  d.meta.ticks_per_rev.reset();
  EXPECT_THAT(message(tracks::Track(d), {}), HasSubstr("robot.ticks_per_rev"));
  d = shared_track().data();
  for (auto& kv : d.meta.extra)
    if (kv.first == "sim.effects") kv.second = "radius_error:scale_l=7";
  EXPECT_THAT(message(tracks::Track(d), {}), AllOf(HasSubstr("'chair'"), HasSubstr("sim.effects")));

  CalibrationInputOptions bad;
  bad.default_v_var = -1.0;
  EXPECT_THAT(message(shared_track(), bad), AllOf(HasSubstr("'chair'"), HasSubstr("default_v_var")));
}

TEST(PoseSeries, WrapInterpolateAndCentralDifferenceOnAnArc) {
  EXPECT_DOUBLE_EQ(core::wrap_angle(kPi), kPi);
  EXPECT_DOUBLE_EQ(core::wrap_angle(-kPi), kPi);
  EXPECT_NEAR(core::wrap_angle(3.0 * kPi / 2.0), -kPi / 2.0, 1e-15);
  EXPECT_NEAR(core::wrap_angle(-7.0), -7.0 + 2.0 * kPi, 1e-15);

  // A constant-velocity arc: V = 0.8 m/s, W = 1.5 rad/s, sampled at 20 Hz.
  const double V = 0.8, W = 1.5, rho = V / W;
  objectives::PoseSeries s;
  for (int i = 0; i <= 40; ++i) {
    const double t = 0.05 * i;
    s.push_back(t, objectives::PlanarPose{rho * std::sin(W * t), rho * (1.0 - std::cos(W * t)), W * t});
  }
  const auto mid = objectives::interpolate_pose(s, 0.125, 0.06);
  ASSERT_TRUE(mid.has_value());
  EXPECT_NEAR(mid->theta_rad, W * 0.125, 1e-12);
  EXPECT_FALSE(objectives::interpolate_pose(s, 0.125, 0.04).has_value());  // gap too long
  EXPECT_FALSE(objectives::interpolate_pose(s, 2.01, 1.0).has_value());    // outside
  const auto v = objectives::central_difference_velocity(s, 1.0, 0.05, 0.06);
  ASSERT_TRUE(v.has_value());
  EXPECT_NEAR(v->v_m_s, V, 1e-12);  // the chord correction makes an arc exact
  EXPECT_NEAR(v->w_rad_s, W, 1e-12);
  EXPECT_FALSE(objectives::central_difference_velocity(s, 1.98, 0.05, 0.06).has_value());
}

}  // namespace
}  // namespace odotune::calibration
