// Importers on the REAL files of ../shared/data/real. Every expected figure
// below is quoted from that dataset's SOURCE.md (independent measurements made
// when the data was added), not from this code's output: sample counts,
// durations, path lengths and dead-reckoning errors. The dead-reckoning checks
// integrate each track's odometry with its own metadata, so a wrong unit, a
// swapped L/R or a misaligned command column makes them fail.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include <odotune/tracks/importers.h>
#include <odotune/tracks/track.h>

namespace odotune::tracks {
namespace {

namespace fs = std::filesystem;

const fs::path kReal = fs::path(ODOTUNE_SHARED_DIR) / "data" / "real";
const fs::path kMrclam = kReal / "mrclam7";
const fs::path kOpti = kReal / "optiodom_diff";
const fs::path kLitw = kReal / "utias_lost_in_the_woods" / "derived" / "litw_series.csv";

std::size_t count_present(const Track& tr, Col c) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < tr.size(); ++i) n += tr.at(c, i) ? 1u : 0u;
  return n;
}

bool strictly_increasing(const std::vector<double>& t) {
  for (std::size_t i = 1; i < t.size(); ++i)
    if (!(t[i] > t[i - 1])) return false;
  return true;
}

double wrap(double a) { return std::remainder(a, 2 * std::numbers::pi); }

void expect_cited(const Track& tr, const std::string& in_source, const std::string& in_citation) {
  EXPECT_EQ(tr.meta().origin, "recorded");
  const auto source = tr.meta().get("source");
  const auto citation = tr.meta().get("citation");
  ASSERT_TRUE(source.has_value());
  ASSERT_TRUE(citation.has_value());
  EXPECT_TRUE(tr.meta().get("licence").has_value());
  EXPECT_NE(source->find(in_source), std::string::npos) << *source;
  EXPECT_NE(citation->find(in_citation), std::string::npos) << *citation;
}

// Nearest row to time `at` that has a ground-truth sample.
std::size_t nearest_gt(const Track& tr, double at) {
  const auto& t = tr.t();
  std::size_t best = tr.size();
  double best_d = 1e300;
  const auto it = std::lower_bound(t.begin(), t.end(), at);
  const auto mid = static_cast<std::size_t>(it - t.begin());
  for (std::size_t i = mid > 50 ? mid - 50 : 0; i < std::min(tr.size(), mid + 50); ++i)
    if (tr.at(Col::gt_x, i) && std::fabs(t[i] - at) < best_d) {
      best_d = std::fabs(t[i] - at);
      best = i;
    }
  return best;
}

// ---------------------------------------------------------------- MRCLAM -----

struct DrError {
  double pos_m, yaw_rad;
};

// SOURCE.md's dead reckoning: commanded (v, w) held between samples and
// integrated exactly (unicycle); start pose = ground truth at the first
// odometry sample; times counted from that sample.
std::vector<DrError> mrclam_dead_reckoning(const Track& tr, const std::vector<double>& after_s) {
  const auto& t = tr.t();
  const auto& v = tr.col(Col::v_cmd);
  const auto& w = tr.col(Col::w_cmd);
  std::vector<std::size_t> odo;
  for (std::size_t i = 0; i < tr.size(); ++i)
    if (tr.at(Col::v_cmd, i)) odo.push_back(i);
  const std::size_t g0 = nearest_gt(tr, t[odo.front()]);
  double x = tr.col(Col::gt_x)[g0], y = tr.col(Col::gt_y)[g0], th = tr.col(Col::gt_theta)[g0];
  const auto step = [](double& px, double& py, double& pth, double vv, double ww, double dt) {
    if (std::fabs(ww) > 1e-12) {
      px += vv / ww * (std::sin(pth + ww * dt) - std::sin(pth));
      py -= vv / ww * (std::cos(pth + ww * dt) - std::cos(pth));
    } else {
      px += vv * dt * std::cos(pth);
      py += vv * dt * std::sin(pth);
    }
    pth += ww * dt;
  };
  std::vector<DrError> out;
  std::size_t next_check = 0;
  for (std::size_t k = 0; k + 1 < odo.size() && next_check < after_s.size(); ++k) {
    const double ta = t[odo[k]], tb = t[odo[k + 1]];
    while (next_check < after_s.size() && t[odo.front()] + after_s[next_check] <= tb) {
      const double at = t[odo.front()] + after_s[next_check];
      double px = x, py = y, pth = th;
      step(px, py, pth, v[odo[k]], w[odo[k]], at - ta);
      const std::size_t g = nearest_gt(tr, at);
      out.push_back({std::hypot(px - tr.col(Col::gt_x)[g], py - tr.col(Col::gt_y)[g]),
                     std::fabs(wrap(pth - tr.col(Col::gt_theta)[g]))});
      ++next_check;
    }
    step(x, y, th, v[odo[k]], w[odo[k]], tb - ta);
  }
  return out;
}

TEST(ImportMrclam, Robot1CountsDurationAndCitation) {
  const Track tr = import_mrclam(kMrclam, 1);
  // SOURCE.md: 58 389 GT samples, 58 598 odometry samples (no repeated stamps in Robot1).
  EXPECT_EQ(count_present(tr, Col::gt_x), 58389u);
  EXPECT_EQ(count_present(tr, Col::gt_theta), 58389u);
  EXPECT_EQ(count_present(tr, Col::v_cmd), 58598u);
  EXPECT_EQ(count_present(tr, Col::w_cmd), 58598u);
  EXPECT_EQ(tr.meta().get("source.odometry_duplicate_stamps"), "0");
  EXPECT_EQ(tr.meta().get("source.groundtruth_duplicate_stamps"), "0");
  EXPECT_TRUE(strictly_increasing(tr.t()));
  EXPECT_EQ(tr.t().front(), 0.0);
  // GT duration 899.99 s; odometry starts 6.2-8.6 s after the ground truth.
  std::size_t g_first = tr.size(), g_last = 0, o_first = tr.size();
  for (std::size_t i = 0; i < tr.size(); ++i) {
    if (tr.at(Col::gt_x, i)) g_first = std::min(g_first, i), g_last = i;
    if (tr.at(Col::v_cmd, i)) o_first = std::min(o_first, i);
  }
  EXPECT_NEAR(tr.t()[g_last] - tr.t()[g_first], 899.99, 0.006);
  EXPECT_GE(tr.t()[o_first] - tr.t()[g_first], 6.2);
  EXPECT_LE(tr.t()[o_first] - tr.t()[g_first], 8.6);
  // First stamp of Robot1_Groundtruth.dat, kept exactly.
  EXPECT_EQ(tr.meta().get("source.t0_unix"), "1248446182.116");
  // Millisecond stamps subtract exactly: every t is the double nearest k/1000.
  for (std::size_t i = 0; i < tr.size(); ++i) {
    const double k = std::round(tr.t()[i] * 1000.0);
    ASSERT_EQ(tr.t()[i], k / 1000.0) << "row " << i;
  }
  EXPECT_FALSE(tr.has_ticks());
  EXPECT_TRUE(tr.has_cmd());
  expect_cited(tr, "Robot1_Odometry.dat", "Leung");
  EXPECT_NE(tr.meta().get("citation")->find("2011"), std::string::npos);
}

TEST(ImportMrclam, Robot1PathLengths) {
  const Track tr = import_mrclam(kMrclam, 1);
  // SOURCE.md: GT path 53.55 m, integral of |v_cmd| dt 55.31 m.
  double gt_path = 0, cmd_path = 0;
  std::size_t pg = tr.size(), po = tr.size();
  for (std::size_t i = 0; i < tr.size(); ++i) {
    if (tr.at(Col::gt_x, i)) {
      if (pg < tr.size())
        gt_path += std::hypot(tr.col(Col::gt_x)[i] - tr.col(Col::gt_x)[pg],
                              tr.col(Col::gt_y)[i] - tr.col(Col::gt_y)[pg]);
      pg = i;
    }
    if (tr.at(Col::v_cmd, i)) {
      if (po < tr.size()) cmd_path += std::fabs(tr.col(Col::v_cmd)[po]) * (tr.t()[i] - tr.t()[po]);
      po = i;
    }
  }
  EXPECT_NEAR(gt_path, 53.55, 0.01);
  EXPECT_NEAR(cmd_path, 55.31, 0.01);
}

TEST(ImportMrclam, Robot1DeadReckoningMatchesSource) {
  const Track tr = import_mrclam(kMrclam, 1);
  // SOURCE.md, robot 1: 0.39 m / 0.82 rad at 60 s, 2.46 m / 0.35 rad at 300 s.
  const auto e = mrclam_dead_reckoning(tr, {60.0, 300.0});
  ASSERT_EQ(e.size(), 2u);
  EXPECT_NEAR(e[0].pos_m, 0.39, 0.015);
  EXPECT_NEAR(e[0].yaw_rad, 0.82, 0.015);
  EXPECT_NEAR(e[1].pos_m, 2.46, 0.015);
  EXPECT_NEAR(e[1].yaw_rad, 0.35, 0.015);
}

TEST(ImportMrclam, RepeatedStampsKeepTheLastSampleAndAreCounted) {
  // Robot2/3_Odometry.dat hold 60 936 / 55 085 lines (SOURCE.md), of which
  // 4 / 7 repeat the stamp of the line before (counted with uniq -d).
  const Track r2 = import_mrclam(kMrclam, 2);
  EXPECT_EQ(r2.meta().get("source.odometry_duplicate_stamps"), "4");
  EXPECT_EQ(count_present(r2, Col::v_cmd), 60936u - 4u);
  EXPECT_EQ(count_present(r2, Col::gt_x), 56529u);
  EXPECT_TRUE(strictly_increasing(r2.t()));

  const Track r3 = import_mrclam(kMrclam, 3);
  EXPECT_EQ(r3.meta().get("source.odometry_duplicate_stamps"), "7");
  EXPECT_EQ(count_present(r3, Col::v_cmd), 55085u - 7u);
  EXPECT_EQ(count_present(r3, Col::gt_x), 53545u);
  // Robot3_Odometry.dat lines 1008/1009: stamp 1248446204.996 with w -> 0.343
  // then 0.341; t0 is 1248446182.116, so the row is at t = 22.880 s.
  const auto it = std::lower_bound(r3.t().begin(), r3.t().end(), 22.8795);
  ASSERT_NE(it, r3.t().end());
  const auto row = static_cast<std::size_t>(it - r3.t().begin());
  EXPECT_DOUBLE_EQ(r3.t()[row], 22.88);
  EXPECT_DOUBLE_EQ(r3.col(Col::w_cmd)[row], 0.341);
  EXPECT_DOUBLE_EQ(r3.col(Col::v_cmd)[row], 0.080);
}

// -------------------------------------------------------------- OptiOdom -----

struct OptiRun {
  const char* file;  // below optiodom_diff/
  std::size_t samples;
  double duration_s, gt_path_m, end_err_m, max_err_m, end_yaw_rad;
};

// The table "Runs included" of optiodom_diff/SOURCE.md.
const OptiRun kOptiRuns[] = {
    {"circular/231220200146/231220200146_run-01.csv", 2066, 103.25, 9.56, 0.080, 0.108, -0.144},
    {"circular/231220200146/231220200146_run-02.csv", 2066, 103.25, 9.55, 0.155, 0.160, +0.255},
    {"free/020120212354/020120212354_run-01.csv", 3183, 159.10, 15.76, 0.165, 0.277, +0.105},
    {"free/030120210001/030120210001_run-01.csv", 1601, 80.00, 7.71, 0.029, 0.044, +0.039},
    {"free/030120210001/030120210001_run-02.csv", 1968, 98.35, 10.77, 0.054, 0.099, +0.009},
    {"square/231220200045/231220200045_run-01.csv", 1394, 69.65, 6.86, 0.042, 0.056, -0.047},
    {"square/231220200045/231220200045_run-02.csv", 1389, 69.40, 6.88, 0.101, 0.102, +0.095},
};

double correlation(const std::vector<double>& a, const std::vector<double>& b) {
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) ma += a[i], mb += b[i];
  ma /= static_cast<double>(a.size());
  mb /= static_cast<double>(b.size());
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return sab / std::sqrt(saa * sbb);
}

void check_optiodom_run(const OptiRun& p) {
  SCOPED_TRACE(p.file);
  const Track tr = import_optiodom(kOpti / p.file);
  EXPECT_EQ(tr.size(), p.samples);
  EXPECT_NEAR(tr.duration_s(), p.duration_s, 1e-6);
  EXPECT_TRUE(strictly_increasing(tr.t()));
  expect_cited(tr, fs::path(p.file).filename().string(), "OptiOdom");
  EXPECT_NE(tr.meta().get("licence")->find("MIT"), std::string::npos);
  // SOURCE.md: ngear 43.7 x encRes 64 = 2796.8 ticks/rev, D = 0.084 m, b = 0.2 m.
  ASSERT_TRUE(tr.meta().ticks_per_rev && tr.meta().wheel_radius_left_m && tr.meta().wheel_radius_right_m &&
              tr.meta().wheel_base_m);
  EXPECT_NEAR(*tr.meta().ticks_per_rev, 2796.8, 1e-9);
  EXPECT_DOUBLE_EQ(*tr.meta().wheel_radius_left_m, 0.042);
  EXPECT_DOUBLE_EQ(*tr.meta().wheel_radius_right_m, 0.042);
  EXPECT_DOUBLE_EQ(*tr.meta().wheel_base_m, 0.2);
  ASSERT_TRUE(tr.has_ticks());
  ASSERT_TRUE(tr.has_gt());

  // Ground truth is relative to the run start; the GT path length.
  EXPECT_EQ(tr.col(Col::gt_x)[0], 0.0);
  EXPECT_EQ(tr.col(Col::gt_theta)[0], 0.0);
  double path = 0;
  for (std::size_t i = 1; i < tr.size(); ++i)
    path += std::hypot(tr.col(Col::gt_x)[i] - tr.col(Col::gt_x)[i - 1],
                       tr.col(Col::gt_y)[i] - tr.col(Col::gt_y)[i - 1]);
  EXPECT_NEAR(path, p.gt_path_m, 0.006);

  // Dead reckoning of the ticks with the track's own metadata (midpoint rule).
  const auto& m = tr.meta();
  const double tpr = *m.ticks_per_rev;
  double x = 0, y = 0, th = 0, max_err = 0, err = 0;
  std::vector<double> v_meas, w_meas, v_cmd, w_cmd;
  for (std::size_t i = 1; i < tr.size(); ++i) {
    const double dl = static_cast<double>(tr.ticks_l()[i] - tr.ticks_l()[i - 1]) * 2 * std::numbers::pi *
                      *m.wheel_radius_left_m / tpr;
    const double dr = static_cast<double>(tr.ticks_r()[i] - tr.ticks_r()[i - 1]) * 2 * std::numbers::pi *
                      *m.wheel_radius_right_m / tpr;
    const double ds = 0.5 * (dl + dr), dth = (dr - dl) / *m.wheel_base_m;
    x += ds * std::cos(th + 0.5 * dth);
    y += ds * std::sin(th + 0.5 * dth);
    th += dth;
    err = std::hypot(x - tr.col(Col::gt_x)[i], y - tr.col(Col::gt_y)[i]);
    max_err = std::max(max_err, err);
    const double dt = tr.t()[i] - tr.t()[i - 1];
    if (tr.has_cmd()) {
      v_meas.push_back(ds / dt);
      w_meas.push_back(dth / dt);
      v_cmd.push_back(tr.col(Col::v_cmd)[i]);
      w_cmd.push_back(tr.col(Col::w_cmd)[i]);
    }
  }
  EXPECT_NEAR(err, p.end_err_m, 0.0015);
  EXPECT_NEAR(max_err, p.max_err_m, 0.0015);
  EXPECT_NEAR(th - tr.col(Col::gt_theta).back(), p.end_yaw_rad, 0.0015);

  // The commands of the robot log align (verified on odoL/odoR) and agree with
  // the measured motion: 60 ticks/cycle is about 0.113 m/s (SOURCE.md).
  ASSERT_TRUE(tr.has_cmd()) << *m.get("source.cmd_alignment");
  EXPECT_NE(m.get("source.cmd_alignment")->find("reproduces"), std::string::npos);
  EXPECT_GT(correlation(v_meas, v_cmd), 0.9);
  EXPECT_GT(correlation(w_meas, w_cmd), 0.5);
  double mean_meas = 0, mean_cmd = 0;
  for (std::size_t i = 0; i < v_meas.size(); ++i) mean_meas += v_meas[i], mean_cmd += v_cmd[i];
  EXPECT_NEAR(mean_cmd / mean_meas, 1.0, 0.05);
}

TEST(ImportOptiOdom, AllSevenRunsMatchTheSourceTable) {
  for (const OptiRun& p : kOptiRuns) check_optiodom_run(p);
}

TEST(ImportOptiOdomOrder, RightBeforeLeftInTheRunFile) {
  // circular run-01: the run file's third row is "...,19,23" (odoR, odoL); the
  // matching _odo.csv row is "4871.2,23,19" (odoL, odoR). So left = 23.
  const Track tr = import_optiodom(kOpti / kOptiRuns[0].file);
  EXPECT_EQ(tr.ticks_l()[2], 23);
  EXPECT_EQ(tr.ticks_r()[2], 19);
  EXPECT_EQ(tr.ticks_l()[3], 23 + 57);
  EXPECT_EQ(tr.ticks_r()[3], 19 + 50);
  // vlin 60 ticks/cycle, omega -0.006634 rad/cycle on the log's second row.
  EXPECT_NEAR(tr.col(Col::v_cmd)[1], 60 * std::numbers::pi * 0.084 / 2796.8 / 0.05, 1e-12);
  EXPECT_NEAR(tr.col(Col::w_cmd)[1], -0.006634 / 0.05, 1e-12);
}

// ------------------------------------------------------------------ LITW -----

TEST(ImportLitw, MatchesSource) {
  const Track tr = import_litw(kLitw);
  // SOURCE.md: 12 609 samples, 0 ... 1260.8 s, 97.4 % valid GT (331 invalid).
  EXPECT_EQ(tr.size(), 12609u);
  EXPECT_NEAR(tr.duration_s(), 1260.8, 1e-9);
  EXPECT_TRUE(strictly_increasing(tr.t()));
  const std::size_t valid = count_present(tr, Col::gt_x);
  EXPECT_EQ(tr.size() - valid, 331u);
  EXPECT_NEAR(100.0 * static_cast<double>(valid) / static_cast<double>(tr.size()), 97.4, 0.05);
  EXPECT_EQ(count_present(tr, Col::gt_theta), valid);
  EXPECT_EQ(count_present(tr, Col::v_cmd), tr.size());
  expect_cited(tr, "litw_series.csv", "Barfoot");
  // Noise variances supplied with the dataset: 0.004420, 0.008186.
  ASSERT_TRUE(tr.meta().get("litw.v_var").has_value());
  ASSERT_TRUE(tr.meta().get("litw.om_var").has_value());
  EXPECT_NEAR(std::stod(*tr.meta().get("litw.v_var")), 0.004420, 5e-7);
  EXPECT_NEAR(std::stod(*tr.meta().get("litw.om_var")), 0.008186, 5e-7);

  // GT path over valid pairs 329.2 m; integral of |v| dt 341.8 m; v in [-0.51, 0.48].
  double gt_path = 0, v_path = 0, vmin = 1e9, vmax = -1e9;
  const auto& v = tr.col(Col::v_cmd);
  for (std::size_t i = 0; i + 1 < tr.size(); ++i) {
    v_path += std::fabs(v[i]) * (tr.t()[i + 1] - tr.t()[i]);
    if (tr.at(Col::gt_x, i) && tr.at(Col::gt_x, i + 1))
      gt_path += std::hypot(tr.col(Col::gt_x)[i + 1] - tr.col(Col::gt_x)[i],
                            tr.col(Col::gt_y)[i + 1] - tr.col(Col::gt_y)[i]);
  }
  for (double s : v) vmin = std::min(vmin, s), vmax = std::max(vmax, s);
  EXPECT_NEAR(gt_path, 329.2, 0.06);
  EXPECT_NEAR(v_path, 341.8, 0.06);
  EXPECT_NEAR(vmin, -0.51, 0.006);
  EXPECT_NEAR(vmax, 0.48, 0.006);
}

}  // namespace
}  // namespace odotune::tracks
