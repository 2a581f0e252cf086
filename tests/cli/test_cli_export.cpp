// End-to-end: `odotune export` from stores made by `odotune grid`, read back by
// `odotune eval --config` and parse_robot_localization_yaml, against the
// store's own rows and closed forms computed here.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <memory>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <odotune/formats/config_yaml.h>
#include <odotune/objectives/param_space.h>
#include <odotune/results/ros_export.h>
#include <odotune/results/store.h>
#include <odotune/tracks/track_io.h>

#include "support/cli_runner.h"

namespace odotune::cli {
namespace {

using results::RunRecord;
using testing_support::reference_track;
using testing_support::run_cli;
using testing_support::slurp;
using testing_support::TempDir;
namespace fs = std::filesystem;

// The best run as export defines it: lowest tuned RMSE, the first stored on ties.
const RunRecord* best_run(const std::vector<RunRecord>& runs, const std::function<bool(const RunRecord&)>& keep,
                          std::size_t* matching = nullptr) {
  const RunRecord* best = nullptr;
  std::size_t n = 0;
  for (const auto& r : runs) {
    if (!keep(r)) continue;
    ++n;
    if (!best || r.tuned.rmse_m < best->tuned.rmse_m) best = &r;
  }
  if (matching) *matching = n;
  return best;
}

double param(const RunRecord& r, const std::string& name) {
  for (std::size_t i = 0; i < r.param_names.size(); ++i)
    if (r.param_names[i] == name) return r.params.at(i);
  ADD_FAILURE() << "no parameter " << name;
  return std::nan("");
}

void expect_rel(double expected, double actual, double rel) {
  EXPECT_NEAR(actual, expected, rel * std::abs(expected)) << "expected " << expected;
}

// ---------------------------------------------------------------------------
// The smoke experiment's store (rq, alpha × track1, track5 × modes 1, 7 × seeds 1, 2).

class CliExport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::make_unique<TempDir>("export");
    const auto r = run_cli(fmt::format("grid {}/experiments/smoke.yaml --store {}", ODOTUNE_SOURCE_DIR,
                                       store().string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() { dir_.reset(); }
  static fs::path store() { return dir_->path() / "smoke.sqlite"; }
  static std::vector<RunRecord> runs() { return results::Store(store()).runs(); }

  static std::unique_ptr<TempDir> dir_;
};
std::unique_ptr<TempDir> CliExport::dir_;

TEST_F(CliExport, OdotuneFormatReplaysToTheStoredTunedRmse) {
  const auto all = runs();
  ASSERT_EQ(all.size(), 16u);
  TempDir tmp;
  for (const std::string model : {"rq", "alpha"}) {
    for (const std::string track : {"track1", "track5"}) {
      SCOPED_TRACE(model + " " + track);
      const RunRecord* want = best_run(all, [&](const RunRecord& r) {
        return r.model == model && r.track == track;
      });
      ASSERT_NE(want, nullptr);
      const fs::path cfg = tmp / (model + "-" + track + ".yaml");
      const auto r = run_cli(fmt::format("export {} --select model={},track={} --format odotune --out {}",
                                         store().string(), model, track, cfg.string()));
      ASSERT_EQ(r.exit_code, 0) << r.err;
      EXPECT_NE(r.out.find("exported run " + results::run_key(*want) + " ("), std::string::npos) << r.out;
      EXPECT_NE(r.out.find(fmt::format("tuned RMSE {:.2f} mm vs baseline {:.2f} mm", want->tuned.rmse_m * 1e3,
                                       want->baseline.rmse_m * 1e3)),
                std::string::npos)
          << r.out;
      EXPECT_NE(r.out.find(cfg.string()), std::string::npos) << r.out;
      EXPECT_NE(slurp(cfg).find(results::run_key(*want)), std::string::npos);  // provenance

      // read_ekf_config gives back the stored parameters.
      const odotune::formats::EkfConfig got = odotune::formats::read_ekf_config(cfg);
      const objectives::ParamSpace space = objectives::ParamSpace::for_model(got.model);
      EXPECT_EQ(filters::to_string(got.model), model);
      const filters::NoiseParams stored = space.to_noise(want->params);
      EXPECT_EQ(got.noise.r_x_m2, stored.r_x_m2);
      EXPECT_EQ(got.noise.r_y_m2, stored.r_y_m2);
      EXPECT_EQ(got.noise.r_theta_rad2, stored.r_theta_rad2);
      EXPECT_EQ(got.noise.q_x_m2, stored.q_x_m2);
      EXPECT_EQ(got.noise.q_y_m2, stored.q_y_m2);
      EXPECT_EQ(got.noise.a1, stored.a1);
      EXPECT_EQ(got.noise.a2, stored.a2);
      const std::vector<double> phys = space.from_noise(got.noise);
      ASSERT_EQ(phys.size(), want->params.size());
      for (std::size_t i = 0; i < phys.size(); ++i) expect_rel(want->params[i], phys[i], 1e-15);

      // eval --config on the same track: exactly the stored tuned RMSE.
      const int index = track == "track1" ? 1 : 5;
      const fs::path json_file = tmp / (model + "-" + track + ".json");
      const auto e = run_cli(fmt::format("eval --config {} --track {} --json {}", cfg.string(),
                                         reference_track(index), json_file.string()));
      ASSERT_EQ(e.exit_code, 0) << e.err;
      const auto j = nlohmann::json::parse(slurp(json_file));
      EXPECT_EQ(j["tracks"][0]["metrics"]["rmse_m"].get<double>(), want->tuned.rmse_m);
      EXPECT_EQ(j["tracks"][0]["baseline"]["rmse_m"].get<double>(), want->baseline.rmse_m);
    }
  }
}

TEST_F(CliExport, SelectionPicksTheLowestTunedRmseOfTheMatchingRuns) {
  const auto all = runs();
  TempDir tmp;
  struct Case {
    std::string select;
    std::function<bool(const RunRecord&)> keep;
  };
  const std::vector<Case> cases = {
      {"--select model=alpha", [](const RunRecord& r) { return r.model == "alpha"; }},
      {"--select model=rq --select mode=7", [](const RunRecord& r) { return r.model == "rq" && r.mode == 7; }},
      {"--select seed=2,model=rq,heldout=none",
       [](const RunRecord& r) { return r.model == "rq" && r.seed == 2; }},
      {"--select mode=1,track=track5 --select model=alpha",
       [](const RunRecord& r) { return r.model == "alpha" && r.mode == 1 && r.track == "track5"; }},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.select);
    std::size_t n = 0;
    const RunRecord* want = best_run(all, c.keep, &n);
    ASSERT_NE(want, nullptr);
    const fs::path out = tmp / "c.yaml";
    const auto r = run_cli(fmt::format("export {} {} --format odotune --out {}", store().string(), c.select,
                                       out.string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("exported run " + results::run_key(*want) + " ("), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(fmt::format("best of {} matching run", n)), std::string::npos) << r.out;
    for (const auto& other : all)
      if (c.keep(other)) {
        EXPECT_LE(want->tuned.rmse_m, other.tuned.rmse_m);
      }
  }
}

TEST_F(CliExport, RobotLocalizationRqIsRTimesTheOdometryRate) {
  const auto all = runs();
  const RunRecord* want = best_run(all,
                                   [](const RunRecord& r) { return r.model == "rq" && r.track == "track5"; });
  ASSERT_NE(want, nullptr);
  // The odometry rate as the simulator recorded it in the track's metadata.
  const tracks::Track t5 = tracks::read_track(reference_track(5));
  const auto rate_text = t5.meta().get("sim.encoders_rate_hz");
  ASSERT_TRUE(rate_text.has_value());
  const double rate = std::stod(*rate_text);
  ASSERT_EQ(rate, 50.0);

  TempDir tmp;
  const fs::path out = tmp / "ekf.yaml";
  const auto r = run_cli(fmt::format("export {} --select model=rq,track=track5 --format robot_localization "
                                     "--node-name my_ekf --out {}",
                                     store().string(), out.string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("exported run " + results::run_key(*want) + " ("), std::string::npos) << r.out;
  const std::string text = slurp(out);
  const results::RosExportParsed p = results::parse_robot_localization_yaml(text, out.string());
  EXPECT_EQ(p.node_name, "my_ekf");
  expect_rel(rate, p.frequency_hz, 1e-9);
  expect_rel(param(*want, "r1_mm2") * rate * 1e-6, p.at(0, 0), 1e-9);
  expect_rel(param(*want, "r2_mm2") * rate * 1e-6, p.at(1, 1), 1e-9);
  expect_rel(param(*want, "r3_rad2") * rate, p.at(5, 5), 1e-9);
  EXPECT_EQ(p.at(0, 1), 0.0);
  EXPECT_EQ(p.at(2, 2), 0.06);  // robot_localization's default for z
  EXPECT_NE(text.find(results::run_key(*want)), std::string::npos);
  // The fix variance goes into a comment for the fix message's covariance.
  for (const auto& [label, name] :
       {std::pair{"covariance[0] (x, x) = ", "q1_mm2"}, std::pair{"covariance[7] (y, y) = ", "q2_mm2"}}) {
    const auto at = text.find(label);
    ASSERT_NE(at, std::string::npos) << label;
    expect_rel(param(*want, name) * 1e-6, std::stod(text.substr(at + std::string(label).size())), 1e-12);
  }
}

// One line on stderr, a non-zero exit, and no output file.
void expect_one_line_failure(const std::string& args, const fs::path& out,
                             const std::vector<std::string>& needles) {
  SCOPED_TRACE(args);
  const auto r = run_cli(args + " --out " + out.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.err.rfind("odotune: ", 0), 0u) << r.err;
  for (const auto& n : needles)
    EXPECT_NE(r.err.find(n), std::string::npos) << "missing '" << n << "': " << r.err;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(r.out, "");
}

TEST_F(CliExport, BadSelectionsAndStoresGiveOneLine) {
  TempDir tmp;
  const fs::path out = tmp / "x.yaml";
  const std::string s = "export " + store().string() + " --format odotune";
  expect_one_line_failure(s + " --select model=gyro", out, {"model=gyro", "model is one of: alpha, rq"});
  expect_one_line_failure(s + " --select model=rq,track=track9", out,
                          {"track=track9", "with model=rq", "track is one of: track1, track5"});
  expect_one_line_failure(s + " --select mode=3", out, {"mode is one of: 1, 7"});
  expect_one_line_failure(s + " --select heldout=track1", out, {"heldout is one of: none"});
  expect_one_line_failure(s + " --select mode=7", out, {"2 models (alpha, rq)", "model="});
  expect_one_line_failure(s, out, {"2 models (alpha, rq)"});
  expect_one_line_failure(s + " --select colour=red", out,
                          {"unknown key 'colour'", "model, track, mode, seed, heldout"});
  expect_one_line_failure(s + " --select model", out, {"expected key=value"});
  expect_one_line_failure(s + " --select seed=two,model=rq", out, {"seed must be a non-negative integer"});
  expect_one_line_failure(s + " --select model=rq --select model=alpha", out, {"model twice"});
  expect_one_line_failure("export " + (tmp / "none.sqlite").string() + " --format odotune", out,
                          {"none.sqlite"});
  std::ofstream(tmp / "junk.sqlite") << "this is not a database\n";
  expect_one_line_failure("export " + (tmp / "junk.sqlite").string() + " --format robot_localization", out,
                          {"junk.sqlite"});
  EXPECT_FALSE(fs::exists(tmp / "none.sqlite"));  // reading never creates a store
}

// ---------------------------------------------------------------------------
// alpha / gyro on straight lines, where the time-averaged R has a closed form.

constexpr double kWheelRadius = 0.05, kWheelBase = 0.3, kGyro = 0.1;

struct Line {
  std::string name;
  double theta0, v_true, dt, duration;
  int rows() const { return static_cast<int>(std::lround(duration / dt)) + 1; }
  // Odometry reports 2 % less distance than driven: fixes pull along the track only.
  double v_odo() const { return v_true / 1.02; }
};

// Straight at heading theta0; wheel rates every row, a gyro that reads a
// constant kGyro (bias; it only feeds the gyro model's |ω_z|), a fix on the
// true position every second and exact ground truth.
tracks::Track line_track(const Line& l) {
  tracks::TrackData d;
  d.meta.name = l.name;
  d.meta.wheel_radius_left_m = kWheelRadius;
  d.meta.wheel_radius_right_m = kWheelRadius;
  d.meta.wheel_base_m = kWheelBase;
  const int fix_every = static_cast<int>(std::lround(1.0 / l.dt));
  const double w = l.v_odo() / kWheelRadius;
  for (int i = 0; i < l.rows(); ++i) {
    const double t = i * l.dt;
    const double x = 0.5 + l.v_true * t * std::cos(l.theta0), y = -1.0 + l.v_true * t * std::sin(l.theta0);
    const bool fix = i > 0 && i % fix_every == 0;
    d.t.push_back(t);
    d.col(tracks::Col::omega_l).push_back(w);
    d.col(tracks::Col::omega_r).push_back(w);
    d.col(tracks::Col::gyro_z).push_back(kGyro);
    d.col(tracks::Col::aps_x).push_back(fix ? x : std::nan(""));
    d.col(tracks::Col::aps_y).push_back(fix ? y : std::nan(""));
    d.col(tracks::Col::gt_x).push_back(x);
    d.col(tracks::Col::gt_y).push_back(y);
    d.col(tracks::Col::gt_theta).push_back(l.theta0);
  }
  return tracks::Track(std::move(d));
}

// Σ over the counted steps (2..N) of diag(R) for a straight line: N = rows − 1
// odometry steps of wheel travel d = v_odo·dt each, σl² = σr² = (α1·d)², and
// (midpoint model, Δθ = 0, k = d/(2D))
//   R_xx = σ²(½cos²θ + 2k²sin²θ), R_yy = σ²(½sin²θ + 2k²cos²θ), R_θθ = 2σ²/D².
struct Sum {
  double x = 0, y = 0, yaw = 0, seconds = 0;
  long steps = 0;
};
void add_line(const Line& l, double alpha1, Sum* s) {
  const double d = l.v_odo() * l.dt, var = std::pow(alpha1 * d, 2), k = d / (2 * kWheelBase);
  const double c = std::cos(l.theta0), sn = std::sin(l.theta0);
  const int steps = l.rows() - 2;
  const double counted = steps;
  s->x += counted * var * (0.5 * c * c + 2 * k * k * sn * sn);
  s->y += counted * var * (0.5 * sn * sn + 2 * k * k * c * c);
  s->yaw += counted * 2 * var / (kWheelBase * kWheelBase);
  s->seconds += counted * l.dt;
  s->steps += steps;
}

TEST(CliExportLines, AlphaAndGyroExportTheTimeAveragedProcessNoise) {
  TempDir tmp;
  const std::vector<Line> lines = {
      {"line_a", 0.5, 0.5, 0.02, 20.0}, {"line_b", -1.0, 0.3, 0.04, 20.0}, {"line_c", 2.0, 0.8, 0.02, 10.0}};
  for (const auto& l : lines) tracks::write_track(line_track(l), tmp / (l.name + ".csv"));
  std::ofstream(tmp / "lines.yaml")
      << "format: odotune-experiment/1\nname: lines\nmodels: [alpha, gyro]\n"
         "tracks: [line_a.csv, line_b.csv, line_c.csv]\nmodes: [1]\nseeds: [1]\nsolver: pso\n"
         "budget: {particles: 8, iterations: 6}\nleave_one_out: true\nstore: s.sqlite\n";
  const auto g = run_cli("grid " + (tmp / "lines.yaml").string());
  ASSERT_EQ(g.exit_code, 0) << g.err;
  const fs::path store = tmp / "s.sqlite";
  const auto all = results::Store(store).runs();
  ASSERT_EQ(all.size(), 12u);

  struct Case {
    std::string select, model;
    std::vector<std::size_t> tuned_on;  // indices into lines
    std::string heldout;
  };
  const std::vector<Case> cases = {{"model=alpha,track=line_a", "alpha", {0}, ""},
                                   {"model=gyro,track=line_b", "gyro", {1}, ""},
                                   {"model=gyro,heldout=line_a", "gyro", {1, 2}, "line_a"},
                                   {"model=alpha,track=all-but-line_c", "alpha", {0, 1}, "line_c"}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.select);
    const RunRecord* run = best_run(all, [&](const RunRecord& r) {
      return r.model == c.model && r.heldout_track == c.heldout &&
             (!c.heldout.empty() || r.track == lines[c.tuned_on[0]].name);
    });
    ASSERT_NE(run, nullptr);
    const double alpha1 = c.model == "alpha" ? param(*run, "alpha1")
                                             : param(*run, "a1") + param(*run, "b1") * kGyro;
    // The tuned filter must use the fixes (α1 > 0), else the check is vacuous.
    ASSERT_GT(alpha1, 1e-4);
    Sum s;
    for (auto i : c.tuned_on) add_line(lines[i], alpha1, &s);

    const fs::path out = tmp / "ekf.yaml";
    const auto r = run_cli(fmt::format("export {} --select {} --format robot_localization --out {}",
                                       store.string(), c.select, out.string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("exported run " + results::run_key(*run) + " ("), std::string::npos) << r.out;
    const std::string text = slurp(out);
    const results::RosExportParsed p = results::parse_robot_localization_yaml(text, out.string());
    expect_rel(s.x / s.seconds, p.at(0, 0), 1e-8);
    expect_rel(s.y / s.seconds, p.at(1, 1), 1e-8);
    expect_rel(s.yaw / s.seconds, p.at(5, 5), 1e-8);
    expect_rel(static_cast<double>(s.steps) / s.seconds, p.frequency_hz, 1e-9);
    EXPECT_EQ(p.at(0, 1), 0.0);
    EXPECT_EQ(p.at(0, 5), 0.0);
    EXPECT_EQ(p.at(6, 6), 0.025);  // robot_localization's default for vx
    for (const char* needle :
         {"time average", "Heading dependence", "off-diagonal", "covariance[0] (x, x) = 0.0036 m²"})
      EXPECT_NE(text.find(needle), std::string::npos) << needle;
    for (auto i : c.tuned_on) EXPECT_NE(text.find(lines[i].name), std::string::npos);
    if (c.model == "gyro") {
      EXPECT_NE(text.find("|ω_z|"), std::string::npos);
    }
  }

  // A moved track: one line asking for --track, no file; with --track it works.
  fs::rename(tmp / "line_b.csv", tmp / "moved_b.csv");
  const fs::path out = tmp / "b.yaml";
  const std::string args = fmt::format(
      "export {} --select model=alpha,track=line_b --format robot_localization", store.string());
  expect_one_line_failure(args, out, {"line_b", "--track"});
  const auto r = run_cli(args + " --track " + (tmp / "moved_b.csv").string() + " --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const RunRecord* run = best_run(all,
                                  [](const RunRecord& x) { return x.model == "alpha" && x.track == "line_b"; });
  ASSERT_NE(run, nullptr);
  Sum s;
  add_line(lines[1], param(*run, "alpha1"), &s);
  expect_rel(s.x / s.seconds, results::parse_robot_localization_yaml(slurp(out)).at(0, 0), 1e-8);
  // The odotune format needs no track.
  EXPECT_EQ(run_cli(fmt::format("export {} --select model=alpha,track=line_b --format odotune --out {}",
                                store.string(), (tmp / "b-odotune.yaml").string()))
                .exit_code,
            0);
}

}  // namespace
}  // namespace odotune::cli
