// The augmented odometry model (odotune/diagnose/effect_model.h) and the windowed
// replay (window_replay.h): names from the effect table, no-op parameters give
// exactly the nominal kinematics (checked against an independent dead
// reckoning), Jet derivatives match central differences, and the model with
// the simulated truth reproduces a simulated track far better than nominal.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/effect_model.h>
#include <odotune/diagnose/finding_kind.h>
#include <odotune/diagnose/window_replay.h>
#include <odotune/sim/effects.h>

#include "diagnose/sim_track.h"

namespace odotune::diagnose {
namespace {

using testing_support::SimTrackOptions;
using testing_support::simulate_track;

DiagInput sim_input(std::vector<std::string> effects, double duration_s = 60.0, bool encoders = true) {
  SimTrackOptions o;
  o.duration_s = duration_s;
  o.effects = std::move(effects);
  o.encoders = encoders;
  return build_diag_input(simulate_track(o));
}

TEST(EffectModel, NamesAndLayoutComeFromTheEffectTable) {
  const auto& table = sim::effect_table();
  ASSERT_EQ(table.size(), static_cast<std::size_t>(kNumEffects));
  for (int i = 0; i < kNumEffects; ++i) {
    EXPECT_EQ(effect_name(static_cast<Effect>(i)), table[static_cast<std::size_t>(i)].name);
    EXPECT_EQ(effect_from_name(table[static_cast<std::size_t>(i)].name), static_cast<Effect>(i));
  }
  EXPECT_EQ(effect_name(Effect::lateral_skid), "lateral_skid");
  EXPECT_EQ(effect_name(Effect::time_offset), "time_offset");
  EXPECT_THROW(effect_from_name("lateral_skd"), std::invalid_argument);

  EXPECT_TRUE(is_gyro_effect(Effect::gyro_bias));
  EXPECT_FALSE(is_gyro_effect(Effect::odometry_bias));

  const EffectSet set = EffectSet::parse({"time_offset:dt=0.02", "radius_error:scale_r=1.01",
                                          "slip_zone:x0=1,x1=2,"
                                          "y0=-1,y1=1,s_l=0.1"});
  const auto layout = param_layout(set);
  std::vector<std::string> names;
  for (const auto& s : layout) names.push_back(s.name);
  const std::vector<std::string> want = {"radius_error.scale_l", "radius_error.scale_r", "slip_zone.x0",
                                         "slip_zone.x1",         "slip_zone.y0",         "slip_zone.y1",
                                         "slip_zone.s_l",        "slip_zone.s_r",        "time_offset.dt"};
  EXPECT_EQ(names, want);
  const std::vector<double> values = pack(set);
  EXPECT_EQ(values, (std::vector<double>{1.0, 1.01, 1, 2, -1, 1, 0.1, 0.0, 0.02}));
  EXPECT_FALSE(layout[2].fitted);  // box fixed
  EXPECT_TRUE(layout[6].fitted);
  EXPECT_EQ(layout[0].lower, 0.5);
  EXPECT_EQ(layout[0].upper, 1.5);
  EXPECT_EQ(layout[8].noop, 0.0);
  EXPECT_EQ(unpack(set, values).to_string(), set.to_string());
  EXPECT_EQ(set.to_string(),
            "radius_error:scale_l=1,scale_r=1.01; slip_zone:x0=1,x1=2,y0=-1,y1=1,s_l=0.1,s_r=0; "
            "time_offset:dt=0.02");

  // odometry_bias: both offsets fitted, no-op 0, the table's +-0.5 bounds.
  const auto bias = param_layout(EffectSet::parse({"odometry_bias:b_w=0.01"}));
  ASSERT_EQ(bias.size(), 2u);
  EXPECT_EQ(bias[0].name, "odometry_bias.b_v");
  EXPECT_EQ(bias[1].name, "odometry_bias.b_w");
  EXPECT_TRUE(bias[0].fitted && bias[1].fitted);
  EXPECT_EQ(bias[0].noop, 0.0);
  EXPECT_EQ(bias[1].lower, -0.5);
  EXPECT_EQ(bias[1].upper, 0.5);

  const auto lag = param_layout(EffectSet().enable(Effect::actuator_lag));
  ASSERT_EQ(lag.size(), 1u);
  EXPECT_GT(lag[0].lower, 0.0);  // tau's range excludes 0
  EXPECT_THROW(EffectSet().enable(Effect::lateral_skid).set(Effect::lateral_skid, "k", 2.0),
               std::invalid_argument);
  EXPECT_THROW(EffectSet().set(Effect::lateral_skid, "k", 0.1), std::invalid_argument);
  EXPECT_THROW(EffectSet::parse({"radius_error:scale=1"}), std::invalid_argument);
}

// A finding's kind is written and read in one place: every effect and
// `unexplained` go through to_string and back, anything else is refused.
TEST(EffectModel, FindingKindNamesRoundTrip) {
  for (int i = 0; i < kNumEffects; ++i) {
    const FindingKind k = static_cast<Effect>(i);
    EXPECT_EQ(to_string(k), effect_name(static_cast<Effect>(i)));
    EXPECT_EQ(finding_kind_from_name(to_string(k)), k);
  }
  EXPECT_EQ(to_string(FindingKind{Unexplained{}}), "unexplained");
  EXPECT_EQ(finding_kind_from_name("unexplained"), FindingKind{Unexplained{}});
  EXPECT_NE(finding_kind_from_name("unexplained"), FindingKind{Effect::radius_error});
  EXPECT_THROW(finding_kind_from_name("Unexplained"), std::invalid_argument);
}

TEST(EffectModel, GyroCorrectionInvertsTheGyroEffects) {
  EffectSet set = EffectSet::parse({"gyro_bias:b=0.01", "gyro_scale:s=1.05"});
  for (double w : {-1.0, 0.0, 0.3}) EXPECT_NEAR(corrected_gyro_rate(set, 1.05 * w + 0.01), w, 1e-15);
  EXPECT_EQ(corrected_gyro_rate(EffectSet(), 0.25), 0.25);
  EXPECT_TRUE(param_layout(set).size() == 2 && !param_layout(set)[0].fitted);
}

// Independent nominal dead reckoning of track-format.md at the odometry nodes.
std::vector<Pose<double>> nominal_nodes(const DiagInput& in) {
  std::vector<Pose<double>> p(in.odo_t_s.size(), Pose<double>{0, 0, 0});
  for (std::size_t k = 0; k + 1 < p.size(); ++k) {
    const double dl = in.radius_l_m * (in.phi_l_rad[k + 1] - in.phi_l_rad[k]);
    const double dr = in.radius_r_m * (in.phi_r_rad[k + 1] - in.phi_r_rad[k]);
    const double v = 0.5 * (dl + dr), w = (dr - dl) / in.wheel_base_m;
    const double m = p[k].th + 0.5 * w;
    const double f = std::abs(w) < 1e-9 ? 1.0 : std::sin(0.5 * w) / (0.5 * w);
    p[k + 1] = {p[k].x + f * v * std::cos(m), p[k].y + f * v * std::sin(m), p[k].th + w};
  }
  return p;
}

TEST(EffectModel, NoEffectsIsTheNominalKinematics) {
  const DiagInput in = sim_input({"radius_error:scale_l=0.99"});
  ASSERT_EQ(in.odo_t_s, in.ref_t_s);  // same 100 Hz instants: predictions sit on nodes
  const auto nodes = nominal_nodes(in);
  const ReplayResult r = replay(in, EffectSet(), 0.0);
  ASSERT_EQ(r.windows.size(), 1u);
  for (std::size_t i = 1; i < nodes.size(); i += 7) {
    ASSERT_NEAR(r.pred_x_m[i], nodes[i].x, 1e-9) << i;
    ASSERT_NEAR(r.pred_y_m[i], nodes[i].y, 1e-9) << i;
    ASSERT_NEAR(r.pred_theta_rad[i], nodes[i].th, 1e-9) << i;
  }
  // The drift is real (the right wheel is nominal, the left smaller): the test can fail.
  EXPECT_GT(r.pos_rmse_m, 0.1);
}

TEST(EffectModel, NoOpParametersReproduceNominalExactly) {
  const DiagInput in = sim_input({"lateral_skid:k=0.03"});
  const ReplayResult nominal = replay(in, EffectSet(), 20.0);
  std::vector<EffectSet> sets;
  for (int e = 0; e < kNumEffects; ++e) {
    const auto eff = static_cast<Effect>(e);
    if (eff == Effect::actuator_lag) continue;  // replays commands on a wheel track (below)
    EffectSet s;
    s.enable(eff);
    if (eff == Effect::radius_step) s.set(eff, "t", 30.0);
    if (eff == Effect::slip_zone)
      s.set(eff, "x0", 1.8).set(eff, "x1", 2.6).set(eff, "y0", -1.0).set(eff, "y1", 1.0);
    sets.push_back(s);
  }
  EffectSet all;
  for (const auto& s : sets)
    for (int e = 0; e < kNumEffects; ++e)
      if (s.on(static_cast<Effect>(e))) {
        all.enable(static_cast<Effect>(e));
        for (std::size_t i = 0; i < s.params(static_cast<Effect>(e)).size(); ++i)
          all.set(static_cast<Effect>(e), sim::effect_table()[static_cast<std::size_t>(e)].params[i].name,
                  s.params(static_cast<Effect>(e))[i]);
      }
  sets.push_back(all);
  for (const EffectSet& s : sets) {
    const ReplayResult r = replay(in, s, 20.0);
    ASSERT_EQ(r.pred_x_m.size(), nominal.pred_x_m.size());
    for (std::size_t i = 0; i < r.pred_x_m.size(); ++i) {
      if (std::isnan(nominal.pred_x_m[i])) continue;
      ASSERT_EQ(r.pred_x_m[i], nominal.pred_x_m[i]) << s.to_string() << " sample " << i;
      ASSERT_EQ(r.pred_y_m[i], nominal.pred_y_m[i]) << s.to_string() << " sample " << i;
      ASSERT_EQ(r.pred_theta_rad[i], nominal.pred_theta_rad[i]) << s.to_string() << " sample " << i;
    }
  }
  // Body-velocity odometry: actuator_lag at its no-op value is the plain command replay.
  const DiagInput cmd = sim_input({}, 40.0, /*encoders=*/false);
  ASSERT_EQ(cmd.odometry, OdometryKind::body_velocity);
  const ReplayResult a = replay(cmd, EffectSet(), 20.0);
  const ReplayResult b = replay(cmd, EffectSet().enable(Effect::actuator_lag), 20.0);
  ASSERT_EQ(a.pred_x_m.size(), b.pred_x_m.size());
  for (std::size_t i = 0; i < a.pred_x_m.size(); ++i)
    if (!std::isnan(a.pred_x_m[i])) {
      ASSERT_EQ(a.pred_x_m[i], b.pred_x_m[i]) << i;
    }
  EXPECT_LT(a.pos_rmse_m, 0.01);  // the ideal robot follows its commands
}

// Jet derivatives of every predicted pose of a window against central
// differences of the double model.
template <int N>
void check_derivatives(const DiagInput& in, const EffectSet& set, double window_s, int window) {
  const EffectModel model(in, set);
  const auto windows = make_windows(in, window_s);
  const Window& w = windows.at(static_cast<std::size_t>(window));
  const std::vector<double> p0 = pack(set);
  ASSERT_EQ(p0.size(), static_cast<std::size_t>(N));
  using J = ceres::Jet<double, N>;
  std::vector<J> pj(N);
  for (int i = 0; i < N; ++i) pj[static_cast<std::size_t>(i)] = J(p0[static_cast<std::size_t>(i)], i);
  const Pose<double> a0 = in.has_ref_heading() ? reference_pose_at(in, w.t_begin_s)
                                               : Pose<double>{1.0, 2.0, 0.5};
  const Pose<J> aj{J(a0.x), J(a0.y), J(a0.th)};
  const std::size_t n = w.ref_end - w.ref_begin;
  std::vector<Pose<J>> out(n);
  replay_window(model, pj.data(), w, aj, in.ref_t_s, out.data());
  const auto& layout = model.layout();
  for (int i = 0; i < N; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    if (!layout[ui].fitted) continue;
    const double h = 1e-6 * std::max(1.0, std::abs(p0[ui]));
    std::vector<double> pp = p0, pm = p0;
    pp[ui] += h, pm[ui] -= h;
    std::vector<Pose<double>> op(n), om(n);
    replay_window(model, pp.data(), w, a0, in.ref_t_s, op.data());
    replay_window(model, pm.data(), w, a0, in.ref_t_s, om.data());
    double max_d = 0.0;
    for (std::size_t r = 0; r < n; r += 5) {
      const double fd[3] = {(op[r].x - om[r].x) / (2 * h), (op[r].y - om[r].y) / (2 * h),
                            (op[r].th - om[r].th) / (2 * h)};
      const double ad[3] = {out[r].x.v[i], out[r].y.v[i], out[r].th.v[i]};
      for (int c = 0; c < 3; ++c) {
        ASSERT_NEAR(ad[c], fd[c], 1e-5 * (1.0 + std::abs(fd[c])))
            << layout[ui].name << " sample " << r << " component " << c;
        max_d = std::max(max_d, std::abs(fd[c]));
      }
    }
    EXPECT_GT(max_d, 1e-6) << layout[ui].name << " does not move the prediction";
  }
}

TEST(EffectModel, JetDerivativesMatchCentralDifferences) {
  const DiagInput in = sim_input({"radius_error:scale_l=0.99,scale_r=1.01"}, 40.0);
  const EffectSet set = EffectSet::parse(
      {"radius_error:scale_l=0.99,scale_r=1.02", "wheel_base_error:scale=1.05",
       "radius_step:t=12.345,scale_l=0.98,scale_r=1.01", "speed_radius:c=0.04", "lateral_skid:k=0.03",
       "longitudinal_slip:k=0.2", "slip_zone:x0=1.8,x1=2.6,y0=-1,y1=1,s_l=0.1,s_r=0.05",
       "time_offset:dt=0.0234", "odometry_bias:b_v=0.01,b_w=-0.02"});
  check_derivatives<18>(in, set, 30.0, 0);

  const DiagInput cmd = sim_input({"actuator_lag:tau=0.2"}, 40.0, /*encoders=*/false);
  check_derivatives<5>(cmd,
                       EffectSet::parse({"lateral_skid:k=0.02", "actuator_lag:tau=0.3",
                                         "time_offset:dt=-0.0166", "odometry_bias:b_v=-0.01,b_w=0.02"}),
                       20.0, 1);
}

// The model with the simulated effect's true values reproduces the ground truth
// far better than the nominal model: the model mirrors the simulator.
TEST(EffectModel, TrueParametersReproduceTheSimulation) {
  const std::vector<std::string> effects = {"radius_error:scale_l=0.985,scale_r=1.01",
                                            "wheel_base_error:scale=1.06",
                                            "radius_step:t=20,scale_l=0.97,scale_r=0.99",
                                            "speed_radius:c=0.06",
                                            "lateral_skid:k=0.04",
                                            "longitudinal_slip:k=0.3",
                                            "slip_zone:x0=1.8,x1=2.6,y0=-1,y1=1,s_l=0.12,s_r=0.04",
                                            "time_offset:dt=0.08",
                                            "odometry_bias:b_v=0.02,b_w=-0.03"};
  for (const auto& e : effects) {
    const DiagInput in = sim_input({e}, 45.0);
    const ReplayResult nominal = replay(in, EffectSet(), 20.0);
    const ReplayResult truth = replay(in, EffectSet::parse({e}), 20.0);
    EXPECT_LT(truth.pos_rmse_m, 0.1 * nominal.pos_rmse_m) << e;
    EXPECT_LT(truth.pos_rmse_m, 0.005) << e;
    // (lateral_skid and time_offset hardly turn the robot: heading stays at
    // the encoder-quantisation level of ~1e-4 rad either way.)
    EXPECT_LT(truth.heading_rmse_rad, std::max(0.1 * nominal.heading_rmse_rad, 1e-3)) << e;
    std::cout << e << ": nominal " << nominal.pos_rmse_m << " m " << nominal.heading_rmse_rad << " rad, truth "
              << truth.pos_rmse_m << " m " << truth.heading_rmse_rad << " rad\n";
  }
  // Actuator lag, on a track whose odometry is the commands.
  const DiagInput cmd = sim_input({"actuator_lag:tau=0.25"}, 45.0, /*encoders=*/false);
  const ReplayResult nominal = replay(cmd, EffectSet(), 20.0);
  const ReplayResult truth = replay(cmd, EffectSet::parse({"actuator_lag:tau=0.25"}), 20.0);
  EXPECT_LT(truth.pos_rmse_m, 0.1 * nominal.pos_rmse_m);
  EXPECT_LT(truth.pos_rmse_m, 0.005);
  std::cout << "lag: nominal " << nominal.pos_rmse_m << " m, truth " << truth.pos_rmse_m << " m\n";
  // odometry_bias on command odometry (the offset added to v_cmd, w_cmd),
  // alone and with the lag and a time offset (the offset commutes with both).
  for (const std::vector<std::string>& specs :
       {std::vector<std::string>{"odometry_bias:b_v=-0.02,b_w=0.03"},
        std::vector<std::string>{"actuator_lag:tau=0.25", "time_offset:dt=0.05",
                                 "odometry_bias:b_v=0.015,b_w=0.02"}}) {
    const DiagInput c = sim_input(specs, 45.0, /*encoders=*/false);
    const ReplayResult nom = replay(c, EffectSet(), 20.0);
    const ReplayResult tru = replay(c, EffectSet::parse(specs), 20.0);
    EXPECT_LT(tru.pos_rmse_m, 0.1 * nom.pos_rmse_m) << specs.back();
    EXPECT_LT(tru.pos_rmse_m, 0.005) << specs.back();
    EXPECT_LT(tru.heading_rmse_rad, 0.1 * nom.heading_rmse_rad) << specs.back();
    std::cout << "commands, " << specs.size() << " effects ending " << specs.back() << ": nominal "
              << nom.pos_rmse_m << " m, truth " << tru.pos_rmse_m << " m\n";
  }
}

TEST(WindowReplay, WindowsCoverTheTrackAndFreeAnchorsAlign) {
  SimTrackOptions o;
  o.duration_s = 70.0;
  o.gt_rate_hz = 0.0;
  o.aps_rate_hz = 1.0;
  o.aps_sigma_m = 0.05;
  const DiagInput in = build_diag_input(simulate_track(o));
  const auto w = make_windows(in, 20.0);
  ASSERT_GE(w.size(), 3u);
  for (std::size_t i = 0; i < w.size(); ++i) {
    EXPECT_EQ(w[i].index, static_cast<int>(i));
    EXPECT_GE(w[i].ref_end - w[i].ref_begin, 3u);
    EXPECT_LE(w[i].t_begin_s, in.ref_t_s[w[i].ref_begin]);
    if (i > 0) {
      EXPECT_EQ(w[i].ref_begin, w[i - 1].ref_end);  // contiguous, no overlap
    }
  }
  EXPECT_EQ(w.back().ref_end, in.ref_t_s.size());
  EXPECT_THROW(make_windows(in, -1.0), std::invalid_argument);
  // Ideal robot, fixes with 5 cm noise: the closed-form anchor leaves the noise only.
  const ReplayResult r = replay(in, EffectSet(), 20.0);
  EXPECT_TRUE(std::isnan(r.heading_rmse_rad));
  EXPECT_GT(r.pos_rmse_m, 0.03);
  EXPECT_LT(r.pos_rmse_m, 0.08);
  // A wrong anchor makes it worse.
  std::vector<Pose<double>> shifted = r.anchors;
  for (auto& a : shifted) a.th += 0.05;
  const EffectModel model(in, EffectSet());
  const ReplayResult worse = replay(model, {}, in, w, {}, &shifted);
  EXPECT_GT(worse.pos_rmse_m, r.pos_rmse_m + 0.02);
}

}  // namespace
}  // namespace odotune::diagnose
