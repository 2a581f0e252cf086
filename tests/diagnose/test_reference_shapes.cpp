// Any reference: build_diag_input and diagnose() accept every mix
// of ground truth and position fixes a recording can have (full ground truth,
// ground truth with gaps, a known start plus fixes, fixes only, fixes at an
// irregular rate, gaps filled by fixes) and refuse only a track with no
// reference sample, in one line.
#include <cmath>
#include <stdexcept>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/diagnosis.h>
#include <odotune/diagnose/sensor_checks.h>
#include <odotune/diagnose/series_interp.h>
#include <odotune/diagnose/window_replay.h>

#include "diagnose/sim_track.h"

namespace odotune::diagnose {
namespace {

using testing_support::SimTrackOptions;
using testing_support::simulate_track;

constexpr double kApsSigma = 0.04;  // [m]

SimTrackOptions run(double duration_s, double gt_rate_hz, double aps_rate_hz) {
  SimTrackOptions o;
  o.duration_s = duration_s;
  o.gt_rate_hz = gt_rate_hz;
  o.gt_sigma_m = 0.002;
  o.aps_rate_hz = aps_rate_hz;
  o.aps_sigma_m = kApsSigma;
  o.effects = {"radius_error:scale_l=0.985,scale_r=1.0"};
  o.seed = 1501;
  return o;
}

// Clears ground truth (x, y, theta) on the rows where drop(i, t) holds.
template <class Drop>
tracks::Track without_gt(const tracks::Track& tr, Drop drop) {
  tracks::TrackData d = tr.data();
  const double nan = std::nan("");
  for (std::size_t i = 0; i < d.t.size(); ++i)
    if (drop(i, d.t[i]))
      for (tracks::Col c : {tracks::Col::gt_x, tracks::Col::gt_y, tracks::Col::gt_theta}) d.col(c)[i] = nan;
  return tracks::Track(std::move(d));
}

// Clears fixes on the rows where drop(i) holds.
template <class Drop>
tracks::Track without_fixes(const tracks::Track& tr, Drop drop) {
  tracks::TrackData d = tr.data();
  const double nan = std::nan("");
  for (std::size_t i = 0; i < d.t.size(); ++i)
    if (drop(i))
      for (tracks::Col c : {tracks::Col::aps_x, tracks::Col::aps_y}) d.col(c)[i] = nan;
  return tracks::Track(std::move(d));
}

bool strictly_increasing(const std::vector<double>& t) {
  for (std::size_t i = 1; i < t.size(); ++i)
    if (!(t[i] > t[i - 1])) return false;
  return true;
}

TEST(ReferenceShapes, DenseGroundTruthMakesFixesRedundant) {
  const DiagInput in = build_diag_input(simulate_track(run(60, 50, 1)));
  EXPECT_EQ(in.reference, ReferenceKind::gt);
  EXPECT_TRUE(in.has_ref_heading());
  EXPECT_EQ(in.ref_fix_samples, 0u);  // every fix lies within 1.5 ground-truth periods of a sample
  EXPECT_EQ(in.ref_gt_samples, in.ref_t_s.size());
  EXPECT_TRUE(in.ref_w.empty());
}

TEST(ReferenceShapes, KnownStartPlusFixesIsAMixedPositionReference) {
  const tracks::Track full = simulate_track(run(120, 50, 2));
  const tracks::Track tr = without_gt(full, [](std::size_t i, double) { return i > 0; });
  const DiagInput in = build_diag_input(tr);
  EXPECT_EQ(in.reference, ReferenceKind::aps);  // most samples are fixes
  EXPECT_EQ(in.ref_gt_samples, 1u);
  EXPECT_NEAR(static_cast<double>(in.ref_fix_samples), 2.0 * tr.duration_s(), 3.0);
  EXPECT_FALSE(in.has_ref_heading());
  ASSERT_EQ(in.ref_w.size(), in.ref_t_s.size());
  EXPECT_TRUE(strictly_increasing(in.ref_t_s));
  EXPECT_DOUBLE_EQ(in.ref_t_s.front(), tr.t().front());
  // The start is stated at 2 mm, the fixes at 40 mm: weight (40/2)^2 against a fix.
  EXPECT_DOUBLE_EQ(in.ref_sigma_m, kApsSigma);
  EXPECT_NEAR(in.ref_w.front(), (kApsSigma / 0.002) * (kApsSigma / 0.002), 1e-9);
  EXPECT_DOUBLE_EQ(in.ref_w[1], 1.0);
}

TEST(ReferenceShapes, GroundTruthWithGapsKeepsItsHeadingAndAnchorsAfterAGap) {
  const tracks::Track tr = without_gt(simulate_track(run(120, 50, 0)), [](std::size_t, double t) {
    return (t >= 20 && t < 47) || (t >= 70 && t < 80);
  });
  const DiagInput in = build_diag_input(tr);
  EXPECT_EQ(in.reference, ReferenceKind::gt);
  EXPECT_TRUE(in.has_ref_heading());
  EXPECT_TRUE(in.ref_w.empty());
  const std::vector<Window> w = make_windows(in, 20.0);
  // [20, 40) has no sample and is dropped; [40, 60) starts at the first sample after the gap.
  ASSERT_GE(w.size(), 4u);
  bool after_gap = false;
  for (const Window& x : w) {
    EXPECT_FALSE(x.t_begin_s > 20.5 && x.t_begin_s < 46.9) << x.t_begin_s;
    if (std::abs(x.t_begin_s - 47.0) < 0.02) after_gap = true;
  }
  EXPECT_TRUE(after_gap);
}

// A gap in which the robot turns by more than half a turn: the heading after
// it must continue the truth's (unwrapped through the gyro's turn), not come
// out a whole turn short, and the sensor checks' bins must not span the gap.
TEST(ReferenceShapes, HeadingIsUnwrappedThroughAGapInWhichTheRobotTurns) {
  SimTrackOptions o = run(120, 50, 0);
  o.effects = {"gyro_bias:b=0.003"};
  const tracks::Track full = simulate_track(o);
  const DiagInput whole = build_diag_input(full);
  // The first 20 s stretch after 10 s over which the true heading turns by 3.6-5.5 rad.
  const auto& t = whole.ref_t_s;
  double gap0 = -1.0;
  for (std::size_t i = 0; i < t.size() && gap0 < 0; ++i) {
    if (t[i] < 10.0 || t[i] > 80.0) continue;
    const double turn = std::abs(interp_held(t, whole.ref_theta_rad, t[i] + 20.0) - whole.ref_theta_rad[i]);
    if (turn > 3.6 && turn < 5.5) gap0 = t[i];
  }
  ASSERT_GT(gap0, 0.0) << "the drive has no such turn";
  const tracks::Track gappy = without_gt(full,
                                         [&](std::size_t, double ti) { return ti > gap0 && ti < gap0 + 20.0; });
  const DiagInput in = build_diag_input(gappy);
  ASSERT_TRUE(in.has_ref_heading());
  ASSERT_LT(in.ref_t_s.size(), t.size());
  for (std::size_t i = 0; i < in.ref_t_s.size(); ++i) {
    const double truth = interp_held(t, whole.ref_theta_rad, in.ref_t_s[i]);
    ASSERT_NEAR(in.ref_theta_rad[i], truth, 1e-9) << "t = " << in.ref_t_s[i];
  }
  const SensorCheck sc = check_sensors(in);
  for (std::size_t k = 0; k < sc.reference.t0_s.size(); ++k)
    EXPECT_FALSE(sc.reference.t0_s[k] <= gap0 && sc.reference.t1_s[k] >= gap0 + 20.0) << "bin spans the gap";
  ASSERT_TRUE(sc.gyro.available);
  EXPECT_NEAR(sc.gyro.bias.value, 0.003, std::max(4 * sc.gyro.bias.std_error, 2e-4));
  EXPECT_TRUE(sc.gyro.bias.departs()) << "z " << sc.gyro.bias.z;
  EXPECT_FALSE(sc.gyro.scale.departs()) << "s " << sc.gyro.scale.value << " z " << sc.gyro.scale.z;
  EXPECT_FALSE(sc.odometry.speed_ratio.departs()) << sc.odometry.speed_ratio.value;
}

TEST(ReferenceShapes, FixesFillTheGroundTruthGapsWithTheirOwnWeight) {
  const tracks::Track tr = without_gt(simulate_track(run(120, 50, 2)),
                                      [](std::size_t, double t) { return t >= 30 && t < 60; });
  const DiagInput in = build_diag_input(tr);
  EXPECT_FALSE(in.has_ref_heading());
  EXPECT_NEAR(static_cast<double>(in.ref_fix_samples), 60.0, 2.0);  // 30 s of 2 Hz fixes in the gap
  ASSERT_EQ(in.ref_w.size(), in.ref_t_s.size());
  EXPECT_EQ(in.reference, ReferenceKind::gt);
  EXPECT_DOUBLE_EQ(in.ref_sigma_m, 0.002);
  for (std::size_t i = 0; i < in.ref_t_s.size(); ++i) {
    const bool in_gap = in.ref_t_s[i] >= 30 && in.ref_t_s[i] < 60;
    EXPECT_DOUBLE_EQ(in.ref_w[i], in_gap ? (0.002 / kApsSigma) * (0.002 / kApsSigma) : 1.0) << in.ref_t_s[i];
  }
}

TEST(ReferenceShapes, IrregularFixesAreUsedAsTheyCome) {
  SimTrackOptions o = run(120, 0, 5);
  const tracks::Track tr = without_fixes(simulate_track(o), [](std::size_t i) { return (i * 7919) % 13 < 8; });
  const DiagInput in = build_diag_input(tr);
  EXPECT_EQ(in.reference, ReferenceKind::aps);
  EXPECT_GT(in.ref_t_s.size(), 150u);
  EXPECT_LT(in.ref_t_s.size(), 400u);
  EXPECT_TRUE(strictly_increasing(in.ref_t_s));
}

TEST(ReferenceShapes, OnlyATrackWithoutAnyReferenceSampleIsRefused) {
  const tracks::Track tr = without_gt(simulate_track(run(30, 50, 0)), [](std::size_t, double) { return true; });
  try {
    (void)build_diag_input(tr);
    FAIL() << "expected a refusal";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_THAT(m, ::testing::HasSubstr("no reference sample"));
    EXPECT_EQ(m.find('\n'), std::string::npos);
  }
}

TEST(ReferenceShapes, KnownStartPlusFixesIsDiagnosed) {
  const tracks::Track tr = without_gt(simulate_track(run(160, 50, 2)),
                                      [](std::size_t i, double) { return i > 0; });
  const Diagnosis d = diagnose(build_diag_input(tr));
  ASSERT_FALSE(d.findings.empty()) << d.note;
  EXPECT_TRUE(d.findings.front().is(Effect::radius_error));
  EXPECT_LT(d.heldout.after_pos_rmse_m, d.heldout.before_pos_rmse_m);
}

TEST(ReferenceShapes, ASinglePoseGivesNoFindingAndSaysWhy) {
  const tracks::Track tr = without_gt(simulate_track(run(30, 50, 0)),
                                      [](std::size_t i, double) { return i > 0; });
  const DiagInput in = build_diag_input(tr);
  ASSERT_EQ(in.ref_t_s.size(), 1u);
  const Diagnosis d = diagnose(in);
  EXPECT_TRUE(d.findings.empty());
  EXPECT_THAT(d.note, ::testing::HasSubstr("too few"));
}

}  // namespace
}  // namespace odotune::diagnose
