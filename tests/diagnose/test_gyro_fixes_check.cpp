// check_gyro_with_fixes (odotune/diagnose/gyro_fixes_check.h): the gyro judged
// against sparse position fixes by gyro-heading dead reckoning.
//  * concealed suite: gyro_scale_fixes_only names the gyro scale within 25 %
//    of its departure; wheel_base_error_fixes_only (the confounded mirror)
//    and none_outdoor_fixes give no gyro verdict;
//  * a gyro bias seen through 1 Hz fixes only (sim_track.h robot) is found
//    within 25 %, and the scale is not blamed;
//  * the scale found with command odometry too (no standstill runs);
//  * no effect on a few seeds, or with outlier fixes: no verdict; the
//    held-out test alone refuses one;
//  * a noise-free track gives the simulated scale and bias back closely;
//  * determinism, options (IsValid, bad values throw), unavailable inputs.
// Each case prints its numbers and time (the suite must stay small).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <iostream>
#include <stdexcept>
#include <string>
#include <string_view>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/gyro_fixes_check.h>
#include <odotune/sim/simulator.h>

#include "concealed_cases.h"
#include "diagnose/sim_track.h"

namespace odotune::diagnose {
namespace {

using testing_support::SimTrackOptions;
using testing_support::simulate_track;

const concealed::ConcealedCase& find_case(std::string_view name) {
  for (const auto& c : concealed::concealed_cases())
    if (c.name == name) return c;
  throw std::invalid_argument("no concealed case " + std::string(name));
}

DiagInput case_input(std::string_view name) {
  return build_diag_input(sim::simulate(concealed::base_scenario(find_case(name))));
}

// Fixes only (no ground truth), sim_track.h's robot.
SimTrackOptions fixes_track(std::uint64_t seed, double duration_s = 200.0) {
  SimTrackOptions o;
  o.duration_s = duration_s;
  o.gt_rate_hz = 0.0;
  o.aps_rate_hz = 1.0;
  o.aps_sigma_m = 0.05;
  o.seed = seed;
  return o;
}

GyroFixesCheck run(const DiagInput& in, std::string_view label, const GyroFixesOptions& o = {}) {
  const auto t0 = std::chrono::steady_clock::now();
  const GyroFixesCheck r = check_gyro_with_fixes(in, o);
  const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const GyroCheck& g = r.gyro;
  std::cout << "[gyro-fixes] " << label << ": s = " << g.scale.value << " +- " << g.scale.std_error << " (z "
            << g.scale.z << ", departs " << g.scale.departs() << "), b = " << g.bias.value << " +- "
            << g.bias.std_error << " (z " << g.bias.z << ", departs " << g.bias.departs()
            << "); held-out p joint " << r.joint.p << " scale " << r.scale_own.p << " bias " << r.bias_own.p
            << "; train s " << r.train_scale << " b " << r.train_bias_radps << "; rmse " << r.nominal_pos_rmse_m
            << " -> " << r.fitted_pos_rmse_m << " m; windows " << r.used_windows.size() << "/" << r.num_windows
            << ", fits " << r.fits << ", " << dt << " s\n";
  return r;
}

// ---- the concealed suite ----------------------------------------------------

TEST(GyroFixesCheck, GyroScaleWithFixesOnlyIsNamed) {
  const auto& c = find_case("gyro_scale_fixes_only");  // s = 0.995, 1 Hz fixes, 50 mm
  const GyroFixesCheck r = run(case_input(c.name), c.name);
  ASSERT_TRUE(r.gyro.available) << r.gyro.unavailable_reason;
  const double truth = 0.995, tol = concealed::expected_tolerance(c.expected[0], c.expected[0].params[0]);
  EXPECT_NEAR(tol, 0.00125, 1e-12);
  EXPECT_NEAR(r.gyro.scale.value, truth, tol);
  EXPECT_TRUE(r.gyro.scale.departs());
  EXPECT_TRUE(r.joint.passed && r.scale_own.passed);
  EXPECT_FALSE(r.gyro.bias.departs());
  // The fit must explain the fixes better than the nominal gyro.
  EXPECT_LT(r.fitted_pos_rmse_m, r.nominal_pos_rmse_m);
  // The training fit alone is close too (it is what the held-out test uses).
  EXPECT_NEAR(r.train_scale, truth, 2 * tol);
}

TEST(GyroFixesCheck, WheelBaseErrorWithFixesOnlyDoesNotBlameTheGyro) {
  const auto& c = find_case("wheel_base_error_fixes_only");  // wheels wrong, gyro right
  const GyroFixesCheck r = run(case_input(c.name), c.name);
  ASSERT_TRUE(r.gyro.available) << r.gyro.unavailable_reason;
  EXPECT_FALSE(r.gyro.scale.departs());
  EXPECT_FALSE(r.gyro.bias.departs());
  // The wheel base error (0.35 %) does not leak into the gyro's scale.
  EXPECT_LT(std::abs(r.gyro.scale.value - 1.0), 0.001);
}

TEST(GyroFixesCheck, NoEffectOutdoorFixesNoVerdict) {
  const GyroFixesCheck r = run(case_input("none_outdoor_fixes"), "none_outdoor_fixes");
  ASSERT_TRUE(r.gyro.available) << r.gyro.unavailable_reason;
  EXPECT_FALSE(r.gyro.scale.departs());
  EXPECT_FALSE(r.gyro.bias.departs());
}

// ---- extra cases on the development robot ---------------------------------

TEST(GyroFixesCheck, GyroBiasWithFixesOnlyIsFound) {
  SimTrackOptions o = fixes_track(911);
  o.effects = {"gyro_bias:b=0.002"};
  const GyroFixesCheck r = run(build_diag_input(simulate_track(o)), "gyro_bias b=0.002");
  ASSERT_TRUE(r.gyro.available) << r.gyro.unavailable_reason;
  EXPECT_NEAR(r.gyro.bias.value, 0.002, 0.25 * 0.002);
  EXPECT_TRUE(r.gyro.bias.departs());
  EXPECT_TRUE(r.bias_own.passed);
  EXPECT_FALSE(r.gyro.scale.departs());
}

TEST(GyroFixesCheck, CommandOdometryGyroScaleIsFound) {
  // gyro_scale_fixes_only with the odometry from v_cmd/w_cmd only: no
  // standstill runs (a zero command does not prove a stop); the base lap's
  // spin and full circles still separate the scale from a bias.
  sim::Scenario sc = concealed::base_scenario(find_case("gyro_scale_fixes_only"));
  sc.sensors.encoders.enabled = false;
  const GyroFixesCheck r = run(build_diag_input(sim::simulate(sc)), "gyro_scale_fixes_only, commands");
  ASSERT_TRUE(r.gyro.available) << r.gyro.unavailable_reason;
  EXPECT_EQ(r.standstill_runs, 0);
  EXPECT_NEAR(r.gyro.scale.value, 0.995, 0.00125);
  EXPECT_TRUE(r.gyro.scale.departs());
  EXPECT_FALSE(r.gyro.bias.departs());
}

TEST(GyroFixesCheck, OutlierFixesMakeNoVerdict) {
  // Three fixes 2 m off (40 sigma) in a no-effect track, one of them held out.
  DiagInput in = build_diag_input(simulate_track(fixes_track(971, 120.0)));
  for (std::size_t i : {std::size_t{30}, std::size_t{70}, in.ref_t_s.size() - 10}) in.ref_x_m[i] += 2.0;
  const GyroFixesCheck r = run(in, "none + 3 outlier fixes");
  ASSERT_TRUE(r.gyro.available) << r.gyro.unavailable_reason;
  EXPECT_FALSE(r.gyro.scale.departs());
  EXPECT_FALSE(r.gyro.bias.departs());
  EXPECT_LT(std::abs(r.gyro.scale.value - 1.0), 0.005);
}

TEST(GyroFixesCheck, NoEffectSeedsNoVerdict) {
  for (std::uint64_t seed : {931u, 932u, 933u}) {
    const GyroFixesCheck r = run(build_diag_input(simulate_track(fixes_track(seed, 120.0))),
                                 "none seed " + std::to_string(seed));
    ASSERT_TRUE(r.gyro.available) << r.gyro.unavailable_reason;
    EXPECT_FALSE(r.gyro.scale.departs()) << seed;
    EXPECT_FALSE(r.gyro.bias.departs()) << seed;
    // The standard errors cover the truth (s = 1, b = 0) at 4.5 sigma.
    EXPECT_LT(std::abs(r.gyro.scale.z), 4.5) << seed;
    EXPECT_LT(std::abs(r.gyro.bias.z), 4.5) << seed;
  }
}

TEST(GyroFixesCheck, HeldOutTestAloneStopsNoise) {
  // With the in-sample significance and relevance switched off, the held-out
  // test must still refuse a verdict on a no-effect track.
  GyroFixesOptions o;
  o.z_threshold = 1e-9;
  o.relevance_factor = 0.0;
  o.min_drift_rad = 0.0;
  const GyroFixesCheck r = run(case_input("none_outdoor_fixes"), "none_outdoor_fixes, held-out gate only", o);
  ASSERT_TRUE(r.gyro.available) << r.gyro.unavailable_reason;
  EXPECT_TRUE(r.gyro.scale.relevant && r.gyro.bias.relevant);  // the other gates are open
  EXPECT_FALSE(r.joint.passed);
  EXPECT_FALSE(r.gyro.scale.departs());
  EXPECT_FALSE(r.gyro.bias.departs());
}

TEST(GyroFixesCheck, NoiseFreeTrackGivesScaleAndBiasBack) {
  SimTrackOptions o = fixes_track(941, 120.0);
  o.gyro_sigma_rad_s = 0.0;
  o.aps_sigma_m = 0.001;
  o.ticks_per_rev = 1 << 20;  // negligible quantisation
  o.effects = {"gyro_scale:s=1.02", "gyro_bias:b=-0.003"};
  const GyroFixesCheck r = run(build_diag_input(simulate_track(o)), "noise-free s=1.02 b=-0.003");
  ASSERT_TRUE(r.gyro.available) << r.gyro.unavailable_reason;
  EXPECT_NEAR(r.gyro.scale.value, 1.02, 2e-4);
  EXPECT_NEAR(r.gyro.bias.value, -0.003, 2e-5);
  EXPECT_TRUE(r.gyro.scale.departs());
  EXPECT_TRUE(r.gyro.bias.departs());
  EXPECT_LT(r.fitted_pos_rmse_m, 0.005);
}

// ---- determinism, options, unavailable inputs ------------------------------

TEST(GyroFixesCheck, SameSeedSameNumbers) {
  SimTrackOptions o = fixes_track(951, 100.0);
  o.effects = {"gyro_scale:s=0.99"};
  GyroFixesOptions opt;
  opt.window_s = 25.0;
  const GyroFixesCheck a = check_gyro_with_fixes(build_diag_input(simulate_track(o)), opt);
  const GyroFixesCheck b = check_gyro_with_fixes(build_diag_input(simulate_track(o)), opt);
  ASSERT_TRUE(a.gyro.available) << a.gyro.unavailable_reason;
  EXPECT_EQ(a.gyro.scale.value, b.gyro.scale.value);
  EXPECT_EQ(a.gyro.scale.std_error, b.gyro.scale.std_error);
  EXPECT_EQ(a.gyro.bias.value, b.gyro.bias.value);
  EXPECT_EQ(a.gyro.bias.std_error, b.gyro.bias.std_error);
  EXPECT_EQ(a.distance_scale, b.distance_scale);
  EXPECT_EQ(a.joint.z, b.joint.z);
  EXPECT_EQ(a.used_windows, b.used_windows);
  EXPECT_EQ(a.heldout_windows, b.heldout_windows);
  // A different seed gives different noise, hence different numbers.
  o.seed = 952;
  const GyroFixesCheck c = check_gyro_with_fixes(build_diag_input(simulate_track(o)), opt);
  EXPECT_NE(a.gyro.scale.value, c.gyro.scale.value);
}

TEST(GyroFixesCheck, OptionsAreValidated) {
  std::string why;
  EXPECT_TRUE(GyroFixesOptions{}.IsValid(&why)) << why;
  const auto bad = [](auto edit, std::string_view field) {
    GyroFixesOptions o;
    edit(o);
    std::string w;
    EXPECT_FALSE(o.IsValid(&w)) << field;
    EXPECT_NE(w.find(field), std::string::npos) << w;
  };
  bad([](GyroFixesOptions& o) { o.window_s = 0; }, "window_s");
  bad([](GyroFixesOptions& o) { o.window_s = std::nan(""); }, "window_s");
  bad([](GyroFixesOptions& o) { o.loss_scale = -1; }, "loss_scale");
  bad([](GyroFixesOptions& o) { o.max_iterations = 0; }, "max_iterations");
  bad([](GyroFixesOptions& o) { o.min_spread_sigmas = -1; }, "min_spread_sigmas");
  bad([](GyroFixesOptions& o) { o.heldout_fraction = 1.0; }, "heldout_fraction");
  bad([](GyroFixesOptions& o) { o.heldout_fraction = 0.0; }, "heldout_fraction");
  bad([](GyroFixesOptions& o) { o.alpha = 0.0; }, "alpha");
  bad([](GyroFixesOptions& o) { o.min_informative = -1; }, "min_informative");
  bad([](GyroFixesOptions& o) { o.z_threshold = 0; }, "z_threshold");
  bad([](GyroFixesOptions& o) { o.relevance_window_s = 0; }, "relevance_window_s");
  bad([](GyroFixesOptions& o) { o.relevance_factor = -1; }, "relevance_factor");
  bad([](GyroFixesOptions& o) { o.min_drift_rad = -1; }, "min_drift_rad");
  bad([](GyroFixesOptions& o) { o.model.accel_half_window_s = -1; }, "model");
  // check_gyro_with_fixes refuses invalid options with one line.
  GyroFixesOptions o;
  o.alpha = 2.0;
  DiagInput in;
  try {
    check_gyro_with_fixes(in, o);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("alpha"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
  }
}

TEST(GyroFixesCheck, UnavailableOrBadInputs) {
  SimTrackOptions o = fixes_track(961, 60.0);
  const DiagInput good = build_diag_input(simulate_track(o));
  {
    DiagInput in = good;
    in.gyro_t_s.clear(), in.gyro_z_radps.clear();
    const GyroFixesCheck r = check_gyro_with_fixes(in);
    EXPECT_FALSE(r.gyro.available);
    EXPECT_EQ(r.gyro.unavailable_reason, "no gyro");
    EXPECT_FALSE(r.gyro.scale.departs());
  }
  {  // 60 s in 40 s windows, not shortened below 40 s: 2 windows, too few for a held-out proof.
    GyroFixesOptions opt;
    opt.window_s = 40.0;
    opt.min_window_s = 40.0;
    const GyroFixesCheck r = check_gyro_with_fixes(good, opt);
    EXPECT_FALSE(r.gyro.available);
    EXPECT_NE(r.gyro.unavailable_reason.find("usable window"), std::string::npos) << r.gyro.unavailable_reason;
  }
  {  // The same track with the default shortest window (20 s): three windows of a third of it.
    GyroFixesOptions opt;
    opt.window_s = 40.0;
    const GyroFixesCheck r = check_gyro_with_fixes(good, opt);
    EXPECT_TRUE(r.gyro.available) << r.gyro.unavailable_reason;
    EXPECT_NEAR(r.window_s, (good.ref_t_s.back() - good.ref_t_s.front()) / 3.0, 1e-9);
    EXPECT_EQ(r.used_windows.size(), 3U);
  }
  {  // mismatched gyro arrays: one clear line
    DiagInput in = good;
    in.gyro_z_radps.pop_back();
    EXPECT_THROW(check_gyro_with_fixes(in), std::invalid_argument);
  }
  {  // non-increasing reference time
    DiagInput in = good;
    in.ref_t_s[5] = in.ref_t_s[4];
    EXPECT_THROW(check_gyro_with_fixes(in), std::invalid_argument);
  }
}

}  // namespace
}  // namespace odotune::diagnose
