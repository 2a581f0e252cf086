// Fusion input (odotune/learned/fusion_input.h) on a small simulated drive
// (fusion_track.h: straight, arc, spin): step times, encoder increments
// against the tick column, ground-truth velocities against the commanded
// cruise velocities, the kinematic odometry against the ground truth within
// the encoders' quantisation, per-step power / external velocity / gyro, the
// omega-column path, and the one-line errors for unusable tracks.
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <odotune/learned/fusion_input.h>
#include <odotune/tracks/body_velocity.h>

#include "support/fusion_track.h"

namespace odotune::learned {
namespace {

using testing_support::fusion_track;
using testing_support::FusionTrackOptions;

constexpr double kPi = std::numbers::pi;

const tracks::Track& shared_track() {
  static const tracks::Track track = fusion_track(FusionTrackOptions{});
  return track;
}
const FusionInput& shared_input() {
  static const FusionInput in = build_fusion_input(shared_track());
  return in;
}

// The track row stamped t_s (within 1 µs); track.size() when none.
std::size_t row_at(const tracks::Track& track, double t_s) {
  for (std::size_t i = 0; i < track.size(); ++i)
    if (std::abs(track.t()[i] - t_s) < 1e-6) return i;
  return track.size();
}

TEST(FusionInput, StepTimesAtTheFusionRate) {
  const tracks::Track& track = shared_track();
  const FusionInput& in = shared_input();
  EXPECT_EQ(in.track_name, "fusion");
  EXPECT_DOUBLE_EQ(in.dt_s, 0.1);
  EXPECT_EQ(in.ticks_per_rev, 2048.0);
  EXPECT_DOUBLE_EQ(in.nominal.wheel_base_m, 0.42);
  ASSERT_GE(in.size(), 100u);
  EXPECT_DOUBLE_EQ(in.t.front(), track.t().front());
  for (std::size_t k = 1; k < in.size(); ++k) ASSERT_NEAR(in.t[k] - in.t[k - 1], 0.1, 1e-9);
  EXPECT_LE(in.t.back(), track.t().back() + 1e-6);
  EXPECT_GT(in.t.back() + 0.1, track.t().back());  // no whole step left out
  for (const auto* v : {&in.dticks_l, &in.dticks_r, &in.v_kin, &in.w_kin, &in.power_l, &in.v_ext, &in.v_ext_var,
                        &in.gyro_z, &in.gt_x, &in.v_true, &in.w_true})
    EXPECT_EQ(v->size(), in.size());
  EXPECT_EQ(in.dticks_l[0], 0.0);
  EXPECT_EQ(in.v_kin[0], 0.0);
  EXPECT_TRUE(std::isnan(in.gyro_z[0]));
  EXPECT_TRUE(std::isnan(in.v_ext[0]));
  EXPECT_TRUE(in.has_gt && in.has_power && in.has_ext && in.has_gyro);
}

TEST(FusionInput, IncrementsAreTheTickDifferences) {
  // The 100 Hz tick rows fall on every 10 Hz step: no interpolation, the
  // increment is the tick column's difference exactly.
  const tracks::Track& track = shared_track();
  const FusionInput& in = shared_input();
  double total_l = 0.0;
  for (std::size_t k = 1; k < in.size(); ++k) {
    const std::size_t a = row_at(track, in.t[k - 1]), b = row_at(track, in.t[k]);
    ASSERT_LT(b, track.size());
    EXPECT_EQ(in.dticks_l[k], static_cast<double>(track.ticks_l()[b] - track.ticks_l()[a])) << k;
    EXPECT_EQ(in.dticks_r[k], static_cast<double>(track.ticks_r()[b] - track.ticks_r()[a])) << k;
    total_l += in.dticks_l[k];
  }
  EXPECT_GT(total_l, 1000.0);  // the robot did drive
}

TEST(FusionInput, GroundTruthVelocitiesMatchTheCommandedCruise) {
  // Steps whose whole interval lies inside a cruise (v_cmd, w_cmd constant at
  // the commanded values of fusion_track.h): straight (0.5, 0), arc (0.4,
  // 0.4 rad/s), spin (0, π/4 rad/s). Tolerance: the ground truth's 10 µm /
  // 1 µrad resolution over 0.1 s and the chord of the arc (< 1e-4).
  const tracks::Track& track = shared_track();
  const FusionInput& in = shared_input();
  const FusionTrackOptions o;
  struct Cruise {
    double v, w;
    int seen = 0;
  };
  std::vector<Cruise> cruises = {{o.straight_speed_m_s, 0.0},
                                 {o.arc_speed_m_s, o.arc_speed_m_s / o.arc_radius_m},
                                 {0.0, o.spin_rate_deg_s * kPi / 180.0}};
  const auto& vc = track.col(tracks::Col::v_cmd);
  const auto& wc = track.col(tracks::Col::w_cmd);
  for (std::size_t k = 1; k < in.size(); ++k) {
    const std::size_t a = row_at(track, in.t[k - 1]), b = row_at(track, in.t[k]);
    for (auto& c : cruises) {
      bool inside = true;
      for (std::size_t i = a; i <= b; ++i)
        inside = inside && std::abs(vc[i] - c.v) < 1e-4 && std::abs(wc[i] - c.w) < 1e-4;
      if (!inside) continue;
      ++c.seen;
      EXPECT_NEAR(in.v_true[k], c.v, 5e-4) << "step " << k;
      EXPECT_NEAR(in.w_true[k], c.w, 5e-4) << "step " << k;
    }
  }
  for (const auto& c : cruises) EXPECT_GE(c.seen, 10) << "cruise v=" << c.v << " w=" << c.w;
}

TEST(FusionInput, KinematicOdometryEqualsTruthWithinQuantisation) {
  // No effect: the encoders count the true rotation, floor-quantised to one
  // count; an increment is off by less than one count per wheel, i.e.
  //   |ΔV| < (1 + 1)/2 · c,   |ΔW| < (1 + 1) · c / D,   c = 2πR/(N·Δt),
  // plus the ground truth's resolution (10 µm, 1 µrad over 0.1 s).
  const FusionInput& in = shared_input();
  const double c = 2.0 * kPi * 0.08 / (2048.0 * 0.1);
  double sum_abs_v = 0.0;
  for (std::size_t k = 1; k < in.size(); ++k) {
    ASSERT_TRUE(std::isfinite(in.v_true[k]));
    EXPECT_LT(std::abs(in.v_kin[k] - in.v_true[k]), c + 3e-4) << "step " << k;
    EXPECT_LT(std::abs(in.w_kin[k] - in.w_true[k]), 2.0 * c / 0.42 + 1e-4) << "step " << k;
    sum_abs_v += std::abs(in.v_kin[k] - in.v_true[k]);
  }
  // Uniform quantisation errors: mean |ΔV| ≈ c/3 (triangular), not c.
  EXPECT_LT(sum_abs_v / static_cast<double>(in.size() - 1), 0.5 * c);
}

TEST(FusionInput, PowerExternalAndGyroPerStep) {
  const tracks::Track& track = shared_track();
  const FusionInput& in = shared_input();
  int checked = 0;
  for (std::size_t k = 1; k < in.size(); ++k) {
    // Rows in (t[k−1], t[k]]: ten 100 Hz rows, the last at t[k].
    const std::size_t a = row_at(track, in.t[k - 1]), b = row_at(track, in.t[k]);
    ASSERT_EQ(b - a, 10u);
    double pl = 0.0, pr = 0.0, g = 0.0;
    for (std::size_t i = a + 1; i <= b; ++i) {
      pl += track.col(tracks::Col::power_l)[i];
      pr += track.col(tracks::Col::power_r)[i];
      g += track.col(tracks::Col::gyro_z)[i];
    }
    EXPECT_NEAR(in.power_l[k], pl / 10.0, 1e-12);
    EXPECT_NEAR(in.power_r[k], pr / 10.0, 1e-12);
    EXPECT_NEAR(in.gyro_z[k], g / 10.0, 1e-12);
    // The 10 Hz external sensor samples at t[k] itself.
    EXPECT_EQ(in.v_ext[k], track.col(tracks::Col::v_ext)[b]);
    EXPECT_EQ(in.w_ext[k], track.col(tracks::Col::w_ext)[b]);
    EXPECT_NEAR(in.v_ext_var[k], 0.02 * 0.02, 1e-12);  // the sensor's σ² from v_ext_var
    EXPECT_NEAR(in.w_ext_var[k], 0.02 * 0.02, 1e-12);
    // The gyro mean is the mean yaw rate up to its noise (σ 0.002/√10) and the
    // sampling of the angular ramps (≤ 2 rad/s² · 5 ms).
    EXPECT_NEAR(in.gyro_z[k], in.w_true[k], 4.0 * 0.002 / std::sqrt(10.0) + 0.011) << k;
    ++checked;
  }
  EXPECT_EQ(checked, static_cast<int>(in.size()) - 1);
}

TEST(FusionInput, OmegaColumnsGiveTheSameIncrements) {
  // The same drive with omega_l/omega_r written and the tick columns dropped:
  // increments from ∫ω dt agree with the ticks within quantisation (one
  // count, plus the omega resolution 1e-4 rad/s × 0.1 s in counts).
  FusionTrackOptions o;
  sim::Scenario sc = testing_support::fusion_scenario(o);
  sc.sensors.encoders.omega = true;
  tracks::TrackData d = sim::simulate(sc).data();
  d.ticks_l.clear();
  d.ticks_r.clear();
  const tracks::Track omega_track(std::move(d));
  const FusionInput a = shared_input();
  const FusionInput b = build_fusion_input(omega_track);
  ASSERT_EQ(a.size(), b.size());
  const double tol = 1.0 + 1e-4 * 0.1 * 2048.0 / (2.0 * kPi) + 0.2;  // + trapezoid on the ramps
  for (std::size_t k = 1; k < a.size(); ++k) {
    EXPECT_NEAR(b.dticks_l[k], a.dticks_l[k], tol) << k;
    EXPECT_NEAR(b.dticks_r[k], a.dticks_r[k], tol) << k;
  }
}

TEST(FusionInput, RateOptionChangesTheSteps) {
  FusionInputOptions opt;
  opt.rate_hz = 20.0;
  const FusionInput in = build_fusion_input(shared_track(), opt);
  EXPECT_DOUBLE_EQ(in.dt_s, 0.05);
  EXPECT_NEAR(static_cast<double>(in.size()), 2.0 * static_cast<double>(shared_input().size()), 2.0);
}

std::string error_of(const tracks::Track& track, const FusionInputOptions& opt = {}) {
  try {
    build_fusion_input(track, opt);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(FusionInput, OneLineErrorsNameTheTrack) {
  auto without = [](auto&& edit) {
    tracks::TrackData d = shared_track().data();
    d.meta.name = "broken_one";
    edit(d);
    return tracks::Track(std::move(d));
  };
  const std::string no_base = error_of(without([](tracks::TrackData& d) { d.meta.wheel_base_m.reset(); }));
  EXPECT_NE(no_base.find("track 'broken_one'"), std::string::npos) << no_base;
  EXPECT_NE(no_base.find("robot.wheel_base"), std::string::npos) << no_base;
  EXPECT_EQ(no_base.find('\n'), std::string::npos);

  const std::string no_tpr = error_of(without([](tracks::TrackData& d) { d.meta.ticks_per_rev.reset(); }));
  EXPECT_NE(no_tpr.find("robot.ticks_per_rev"), std::string::npos) << no_tpr;

  // Without wheels, the commands (the simulator says what they are) are the
  // odometry; without them too, there is none.
  const tracks::Track commands = without([](tracks::TrackData& d) {
    d.ticks_l.clear();
    d.ticks_r.clear();
  });
  EXPECT_EQ(build_fusion_input(commands).input, tracks::OdometryInput::commands);
  const std::string no_odo = error_of(without([](tracks::TrackData& d) {
    d.ticks_l.clear();
    d.ticks_r.clear();
    d.col(tracks::Col::v_cmd).clear();
    d.col(tracks::Col::w_cmd).clear();
  }));
  EXPECT_NE(no_odo.find("track 'broken_one': no odometry"), std::string::npos) << no_odo;

  FusionInputOptions bad;
  bad.rate_hz = 0.0;
  const std::string bad_rate = error_of(shared_track(), bad);
  EXPECT_NE(bad_rate.find("rate_hz = 0"), std::string::npos) << bad_rate;
  EXPECT_NE(bad_rate.find("track 'fusion'"), std::string::npos) << bad_rate;

  // A recording shorter than one step.
  const std::string short_one = error_of(without([](tracks::TrackData& d) {
    const std::size_t keep = 5;  // 40 ms of 100 Hz rows
    d.t.resize(keep);
    for (auto& c : d.cols)
      if (!c.empty()) c.resize(keep);
    d.ticks_l.resize(keep);
    d.ticks_r.resize(keep);
  }));
  EXPECT_NE(short_one.find("fewer than 2 steps"), std::string::npos) << short_one;
}

// The simulator's commands as the odometry: each step's mean of the held
// command; with a scale and a delay (calibrated kinematics) the same means
// scaled and taken that much earlier; a calibrated geometry for wheels.
TEST(FusionInput, CommandsAndCalibratedKinematics) {
  const tracks::Track& track = shared_track();
  FusionInputOptions o;
  o.input = tracks::OdometryInput::commands;
  const FusionInput in = build_fusion_input(track, o);
  EXPECT_EQ(in.input, tracks::OdometryInput::commands);
  EXPECT_EQ(in.ticks_per_rev, 0.0);
  EXPECT_TRUE(std::isnan(in.dticks_l[5]));
  const tracks::BodyVelocityIntegral body(track);
  for (std::size_t k = 1; k < in.size(); k += 37) {
    const auto m = body.mean(in.t[k - 1], in.t[k]);
    EXPECT_DOUBLE_EQ(in.v_kin[k], m[0]) << k;
    EXPECT_DOUBLE_EQ(in.w_kin[k], m[1]) << k;
  }
  o.twist.scale_v = 0.9;
  o.twist.scale_w = 1.1;
  o.twist.delay_s = 0.25;
  const FusionInput cal = build_fusion_input(track, o);
  for (std::size_t k = 5; k < in.size(); k += 37) {
    const auto m = body.mean(in.t[k - 1] - 0.25, in.t[k] - 0.25);
    EXPECT_NEAR(cal.v_kin[k], 0.9 * m[0], 1e-12) << k;
    EXPECT_NEAR(cal.w_kin[k], 1.1 * m[1], 1e-12) << k;
  }
  FusionInputOptions g;
  g.geometry = shared_input().nominal;
  g.geometry->wheel_base_m *= 2.0;
  const FusionInput wide = build_fusion_input(track, g);
  for (std::size_t k = 1; k < wide.size(); k += 37) {
    EXPECT_DOUBLE_EQ(wide.v_kin[k], shared_input().v_kin[k]);
    EXPECT_NEAR(wide.w_kin[k], 0.5 * shared_input().w_kin[k], 1e-12);
  }
  FusionInputOptions bad;
  bad.twist.delay_s = -1.0;
  EXPECT_THROW(build_fusion_input(track, bad), std::invalid_argument);
}

TEST(FusionInput, NoGroundTruthGivesNaNTruth) {
  FusionTrackOptions o;
  o.gt = false;
  const FusionInput in = build_fusion_input(fusion_track(o));
  EXPECT_FALSE(in.has_gt);
  EXPECT_TRUE(std::isnan(in.gt_x[3]));
  EXPECT_TRUE(std::isnan(in.v_true[3]));
}

}  // namespace
}  // namespace odotune::learned
