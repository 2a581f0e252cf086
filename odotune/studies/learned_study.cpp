#include <odotune/studies/learned_study.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/non_finite.h>
#include <odotune/core/stopwatch.h>
#include <odotune/core/why.h>
#include <odotune/sim/motion_profile.h>
#include <odotune/sim/random_slip.h>
#include <odotune/sim/simulator.h>
#include <odotune/sim/slip_episodes.h>

namespace odotune::studies {

namespace {

using core::seconds_since;

using core::kNaN;
// 5 simulations, the extra slip drives, 2 trainings, 1 + 3 + 3 evaluations.
long stage_count(const LearnedStudyOptions& o) { return 14 + (o.slip_drives - 1); }

struct Stage {
  const LearnedStudyProgress& progress;
  long total;
  long done = 0;
  void next(const std::string& name) {
    if (progress) progress(done, total, name);
    ++done;
  }
  void finish() {
    if (progress) progress(total, total, "done");
  }
};

// Mean squared error pooled over several series pairs (NaN where none).
double pooled_mean_squared_error(const std::vector<const std::vector<double>*>& est,
                                 const std::vector<const std::vector<double>*>& truth) {
  std::vector<double> e, t;
  for (std::size_t i = 0; i < est.size(); ++i) {
    e.insert(e.end(), est[i]->begin(), est[i]->end());
    t.insert(t.end(), truth[i]->begin(), truth[i]->end());
  }
  return mean_squared_error(e, t);
}

PathSeries path_of(const learned::PoseTrack& p) { return {p.x, p.y, p.theta}; }
PathSeries truth_path(const learned::FusionInput& in) { return {in.gt_x, in.gt_y, in.gt_theta}; }

// `base`: a fresh training's defaults, or default_retrain_training() for refits.
learned::LstmTrainingOptions training_options(const LearnedStudyOptions& o, int iterations,
                                              learned::LstmTrainingOptions base = {}) {
  learned::LstmTrainingOptions t = base;
  t.max_iterations = iterations;
  t.seed = o.seed;
  t.num_threads = o.threads;
  return t;
}

// The fusion of the study: UKF defaults, the given odometry and variance.
learned::LearnedFusionOptions fusion_options(const LearnedStudyOptions& o,
                                             learned::LearnedFusionOptions::Odometry odometry,
                                             const learned::SlipDetectorModel* detector, double static_var_v,
                                             double static_var_w, bool retrain,
                                             double gyro_var = learned::UkfSensorNoise{}.gyro_var) {
  learned::LearnedFusionOptions f;
  f.noise.gyro_var = gyro_var;
  f.odometry = odometry;
  f.detector = detector;
  f.static_var_v = static_var_v;
  f.static_var_w = static_var_w;
  f.retrain.enabled = retrain;
  f.retrain.samples_per_retrain = o.samples_per_retrain;
  f.retrain.training = training_options(o, o.retrain_iterations, learned::default_retrain_training());
  return f;
}

Table3Row table3_row(const std::string& name, const learned::FusionInput& in,
                     const learned::LearnedFusionResult& r) {
  Table3Row row;
  row.name = name;
  row.healthy = r.filter.healthy;
  learned::PoseTrack pose{r.filter.x, r.filter.y, r.filter.theta};
  row.filter = learned::odometry_errors(in, r.filter.v, r.filter.w, r.filter.var_v, r.filter.var_w,
                                        r.filter.cov_vw, &pose);
  row.odometry = learned::odometry_errors(in, r.odometry.v, r.odometry.w, r.odo_var_v, r.odo_var_w, {});
  row.path = path_of(pose);
  row.odo_var_v = r.odo_var_v;
  row.odo_var_w = r.odo_var_w;
  return row;
}

Table2Row table2_row(const std::string& name, const learned::FusionInput& in, const learned::FusionInput& after,
                     std::size_t change_step, const learned::OdometrySeries& odo) {
  Table2Row row;
  row.name = name;
  row.whole = odometry_only_errors(in, odo);
  row.after = odometry_only_errors(after, {slice_series(odo.v, change_step), slice_series(odo.w, change_step)});
  row.v_abs_error = abs_errors(odo.v, in.v_true);
  row.w_abs_error = abs_errors(odo.w, in.w_true);
  return row;
}

void check_role(const sim::Scenario& s, const char* role, bool power, bool slip, bool fusion, bool step) {
  const std::string name = fmt::format("{} scenario '{}'", role, s.name);
  std::string why;
  if (!sim::validate_scenario(s, &why)) throw std::invalid_argument(name + ": " + why);
  if (!s.sensors.encoders.enabled) throw std::invalid_argument(name + ": needs encoders (sensors.encoders)");
  if (!s.sensors.ground_truth.enabled)
    throw std::invalid_argument(name + ": needs ground truth (sensors.ground_truth)");
  if (power && !s.sensors.power.enabled)
    throw std::invalid_argument(name + ": needs motor power (sensors.power) for the slip detector");
  if (slip && s.slip_episodes.empty())
    throw std::invalid_argument(name + ": needs slip episodes (slip_episodes)");
  if (fusion && !s.sensors.ext_velocity.enabled)
    throw std::invalid_argument(name +
                                ": needs the external velocity sensor (sensors.ext_velocity) for the UKF");
  if (fusion && !s.sensors.gyro.enabled)
    throw std::invalid_argument(name + ": needs the gyro (sensors.gyro) for the UKF");
  if (step && !s.effects.radius_step)
    throw std::invalid_argument(name + ": needs a radius change (effects.radius_step)");
}

// 1. Simulate: the five roles' tracks (seeds options.seed + 0..4) as fusion
// inputs in kLearnedScenarioRoles order; `slip_eval_episodes` gets the
// slip_eval track's episodes.
std::vector<learned::FusionInput> simulate_roles(const LearnedStudyScenarios& scenarios,
                                                 const LearnedStudyOptions& options,
                                                 const learned::FusionInputOptions& fo, Stage& stage,
                                                 LearnedStudy& out,
                                                 std::vector<sim::SlipEpisode>& slip_eval_episodes) {
  const sim::Scenario* roles[] = {&scenarios.learn, &scenarios.eval, &scenarios.step, &scenarios.slip,
                                  &scenarios.slip_eval};
  std::vector<learned::FusionInput> inputs;
  for (std::size_t i = 0; i < 5; ++i) {
    stage.next(fmt::format("simulating {}", roles[i]->name));
    sim::Scenario s = *roles[i];
    s.seed = options.seed + i;
    const tracks::Track track = sim::simulate(s);
    out.scenario_names.push_back(roles[i]->name);
    out.track_names.push_back(track.name());
    try {
      inputs.push_back(learned::build_fusion_input(track, fo));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(fmt::format("{} scenario '{}': {}", kLearnedScenarioRoles[i], roles[i]->name,
                                              e.what()));
    }
    if (!inputs.back().has_gt)
      throw std::invalid_argument(fmt::format("{} scenario '{}': the simulated track has no ground truth",
                                              kLearnedScenarioRoles[i], roles[i]->name));
    if (i == 4) slip_eval_episodes = sim::slip_episodes_from_metadata(track.meta());
  }
  return inputs;
}

// The extra drives of the slip route, with random episode layouts; records
// every slip drive (the scenario's own first) in out.slip_drives.
std::vector<learned::FusionInput> simulate_extra_slip_drives(const LearnedStudyScenarios& scenarios,
                                                             const LearnedStudyOptions& options,
                                                             const learned::FusionInputOptions& fo,
                                                             Stage& stage, LearnedStudy& out) {
  out.slip_drives.push_back({options.seed + 3, scenarios.slip.slip_episodes});
  std::vector<learned::FusionInput> extra;
  const sim::MotionProfile route(scenarios.slip.motion);
  for (int j = 1; j < options.slip_drives; ++j) {
    sim::Scenario s = scenarios.slip;
    s.seed = options.seed + 4 + static_cast<std::uint64_t>(j);
    s.slip_episodes = sim::random_slip_episodes(route, s.seed);
    s.name = fmt::format("{}_random{}", scenarios.slip.name, j);
    stage.next(fmt::format("simulating {}", s.name));
    if (s.slip_episodes.empty())
      throw std::invalid_argument(
          fmt::format("slip scenario '{}': its route has no stretch long and fast enough "
                      "for a random slip episode (odotune/sim/random_slip.h)",
                      scenarios.slip.name));
    out.slip_drives.push_back({s.seed, s.slip_episodes});
    extra.push_back(learned::build_fusion_input(sim::simulate(s), fo));
  }
  return extra;
}

// 2. Train the velocity nets on `learn` (and the kinematic odometry's MAE
// there, for comparison).
void train_velocity_nets(const learned::FusionInput& learn, const LearnedStudyOptions& options, Stage& stage,
                         LearnedStudy& out) {
  stage.next("training the velocity nets");
  learned::LearnedTrainingOptions lo;
  lo.training = training_options(options, options.iterations);
  lo.previous_noise_v = options.previous_noise_v;
  lo.previous_noise_w = options.previous_noise_w;
  out.model = learned::train_learned_odometry({&learn}, lo, &out.training.odometry);
  const learned::OdometrySeries learn_kin = learned::kinematic_odometry(learn);
  out.training.kinematic_v_mae = learned::series_errors(learn_kin.v, learn.v_true, {}).mae;
  out.training.kinematic_w_mae = learned::series_errors(learn_kin.w, learn.w_true, {}).mae;
}

// The slip detector, trained on the slip drives; fills the nets' and the
// kinematic odometry on each drive.
void train_detector(const std::vector<const learned::FusionInput*>& slips, const LearnedStudyOptions& options,
                    Stage& stage, LearnedStudy& out, std::vector<learned::OdometrySeries>& slip_lstm,
                    std::vector<learned::OdometrySeries>& slip_kin) {
  stage.next("training the slip detector");
  for (const learned::FusionInput* in : slips) {
    slip_lstm.push_back(learned::run_learned_odometry(*in, out.model));
    slip_kin.push_back(learned::kinematic_odometry(*in));
  }
  learned::SlipTrainingOptions so;
  so.training = training_options(options, options.iterations);
  so.stride = options.slip_stride;
  out.detector = learned::train_slip_detector(slips, slip_lstm, so, &out.training.detector);
}

// 3. Static variances, pooled over the detector's training drives; throws
// when one is not finite and > 0.
void set_static_variances(const std::vector<const learned::FusionInput*>& slips,
                          const std::vector<learned::OdometrySeries>& slip_lstm,
                          const std::vector<learned::OdometrySeries>& slip_kin, const std::string& slip_name,
                          LearnedStudy& out) {
  std::array<std::vector<const std::vector<double>*>, 6> series;  // lstm v, w; kin v, w; true v, w
  std::vector<const std::vector<double>*> gyro, gyro_truth;
  for (std::size_t i = 0; i < slips.size(); ++i) {
    if (slips[i]->has_gyro) gyro.push_back(&slips[i]->gyro_z), gyro_truth.push_back(&slips[i]->w_true);
    series[0].push_back(&slip_lstm[i].v);
    series[1].push_back(&slip_lstm[i].w);
    series[2].push_back(&slip_kin[i].v);
    series[3].push_back(&slip_kin[i].w);
    series[4].push_back(&slips[i]->v_true);
    series[5].push_back(&slips[i]->w_true);
  }
  out.static_var_lstm_v = pooled_mean_squared_error(series[0], series[4]);
  out.static_var_lstm_w = pooled_mean_squared_error(series[1], series[5]);
  out.static_var_kin_v = pooled_mean_squared_error(series[2], series[4]);
  out.static_var_kin_w = pooled_mean_squared_error(series[3], series[5]);
  if (gyro.size() == slips.size()) out.static_var_gyro = pooled_mean_squared_error(gyro, gyro_truth);
  for (double v : {out.static_var_lstm_v, out.static_var_lstm_w, out.static_var_kin_v, out.static_var_kin_w,
                   out.static_var_gyro})
    if (!(v > 0.0) || !std::isfinite(v))
      throw std::invalid_argument(
          fmt::format("slip scenario '{}': the odometry's mean squared error there is {}: "
                      "expected a finite value > 0 for the static variance",
                      slip_name, v));
}

// 4. Table 1: the nets' and the kinematic odometry on the evaluation track.
void table1(const learned::FusionInput& eval, Stage& stage, LearnedStudy& out) {
  stage.next("Table 1: odometry on the evaluation track");
  Table1Result& t = out.table1;
  t.track = eval.track_name;
  const learned::OdometrySeries lstm = learned::run_learned_odometry(eval, out.model);
  const learned::OdometrySeries kin = learned::kinematic_odometry(eval);
  t.rows = {{"LSTM odometry", studies::odometry_only_errors(eval, lstm)},
            {"Traditional odometry", odometry_only_errors(eval, kin)}};
  t.truth = truth_path(eval);
  t.lstm = path_of(learned::dead_reckon(eval, lstm.v, lstm.w));
  t.traditional = path_of(learned::dead_reckon(eval, kin.v, kin.w));
}

// Table 2's record of one retraining of the nets.
RetrainRecord retrain_record(const learned::RetrainEvent& e) {
  RetrainRecord rec;
  rec.step = e.step;
  rec.t_s = e.t_s;
  rec.ms = 1e3 * e.seconds;
  rec.v_cost_before = e.v.initial_cost;
  rec.v_cost_after = e.v.final_cost;
  rec.v_mae_after = e.v.train_mae;
  rec.w_cost_before = e.w.initial_cost;
  rec.w_cost_after = e.w.final_cost;
  rec.w_mae_after = e.w.train_mae;
  rec.v_iterations = e.v.iterations;
  rec.w_iterations = e.w.iterations;
  return rec;
}

// 5. Table 2: the nets with and without retraining, and the kinematic
// odometry, on the step track (whole, and after the radius change).
void table2(const learned::FusionInput& step, const sim::Scenario& step_scenario,
            const LearnedStudyOptions& options, Stage& stage, LearnedStudy& out) {
  Table2Result& t = out.table2;
  t.track = step.track_name;
  t.t_s = step.t;
  t.truth = truth_path(step);
  t.change_t_s = step_scenario.effects.radius_step->t;
  t.change_step = static_cast<std::size_t>(std::lower_bound(step.t.begin(), step.t.end(), t.change_t_s) -
                                           step.t.begin());
  if (t.change_step == 0) t.change_step = 1;
  if (t.change_step + 2 > step.size())
    throw std::invalid_argument(fmt::format("step scenario '{}': the radius change at {} s is not inside the "
                                            "track (which ends at {} s)",
                                            step_scenario.name, t.change_t_s, step.t.back()));
  const learned::FusionInput after = slice_fusion_input(step, t.change_step);
  const learned::SlipDetectorModel* det = step.has_power ? &out.detector : nullptr;
  using Odo = learned::LearnedFusionOptions::Odometry;

  stage.next("Table 2: LSTM with retraining");
  const learned::LearnedFusionResult re = learned::run_learned_fusion(
      step, &out.model,
      fusion_options(options, Odo::learned, det, out.static_var_lstm_v, out.static_var_lstm_w, true));
  Table2Row r = table2_row("LSTM retraining", step, after, t.change_step, re.odometry);
  r.retrains = static_cast<int>(re.retrains.size());
  double ms = 0.0;
  for (const learned::RetrainEvent& e : re.retrains) {
    const RetrainRecord rec = retrain_record(e);
    ms += rec.ms;
    t.retrains.push_back(rec);
  }
  if (!re.retrains.empty()) r.ms_per_retrain = ms / static_cast<double>(re.retrains.size());
  t.rows.push_back(std::move(r));

  stage.next("Table 2: LSTM without retraining");
  const learned::LearnedFusionResult no = learned::run_learned_fusion(
      step, &out.model,
      fusion_options(options, Odo::learned, det, out.static_var_lstm_v, out.static_var_lstm_w, false));
  t.rows.push_back(table2_row("LSTM no retraining", step, after, t.change_step, no.odometry));

  stage.next("Table 2: traditional odometry");
  // The kinematic odometry does not depend on the filter.
  t.rows.push_back(table2_row("Traditional odometry", step, after, t.change_step,
                              learned::kinematic_odometry(step)));
}

// 6. Table 3: the UKF fusing the nets with variable or static covariance, and
// the kinematic odometry with static covariance, on the slip evaluation track.
void table3(const learned::FusionInput& slip_eval, const std::vector<sim::SlipEpisode>& episodes,
            const LearnedStudyOptions& options, Stage& stage, LearnedStudy& out) {
  Table3Result& t = out.table3;
  t.track = slip_eval.track_name;
  t.t_s = slip_eval.t;
  t.truth = truth_path(slip_eval);
  t.episodes = episodes;
  using Odo = learned::LearnedFusionOptions::Odometry;
  stage.next("Table 3: LSTM + variable covariance");
  const learned::LearnedFusionResult var = learned::run_learned_fusion(
      slip_eval, &out.model,
      fusion_options(options, Odo::learned, &out.detector, out.static_var_lstm_v, out.static_var_lstm_w, false,
                     out.static_var_gyro));
  t.rows.push_back(table3_row("LSTM odometry + variable covariance", slip_eval, var));
  t.lstm_sq_error_v = abs_errors(var.odometry.v, slip_eval.v_true);
  t.lstm_sq_error_w = abs_errors(var.odometry.w, slip_eval.w_true);
  for (double& e : t.lstm_sq_error_v) e *= e;
  for (double& e : t.lstm_sq_error_w) e *= e;

  stage.next("Table 3: traditional + static covariance");
  const learned::LearnedFusionResult kin = learned::run_learned_fusion(
      slip_eval, nullptr,
      fusion_options(options, Odo::kinematic, nullptr, out.static_var_kin_v, out.static_var_kin_w, false,
                     out.static_var_gyro));
  t.rows.push_back(table3_row("Traditional odometry + static covariance", slip_eval, kin));

  stage.next("Table 3: LSTM + static covariance");
  const learned::LearnedFusionResult fixed = learned::run_learned_fusion(
      slip_eval, &out.model,
      fusion_options(options, Odo::learned, nullptr, out.static_var_lstm_v, out.static_var_lstm_w, false,
                     out.static_var_gyro));
  t.rows.push_back(table3_row("LSTM odometry + static covariance", slip_eval, fixed));
}

}  // namespace

bool LearnedStudyOptions::IsValid(std::string* why) const {
  if (iterations < 1 || iterations > 10000)
    return core::invalid(why, fmt::format("iterations = {} must be in 1..10000", iterations));
  if (retrain_iterations < 1 || retrain_iterations > 10000)
    return core::invalid(why, fmt::format("retrain_iterations = {} must be in 1..10000", retrain_iterations));
  if (samples_per_retrain < 20 || samples_per_retrain > 100000)
    return core::invalid(why,
                         fmt::format("samples_per_retrain = {} must be in 20..100000", samples_per_retrain));
  if (!(rate_hz > 0.0 && rate_hz <= 1000.0))
    return core::invalid(why, fmt::format("rate_hz = {} must be in (0, 1000]", rate_hz));
  if (!(previous_noise_v >= 0.0 && std::isfinite(previous_noise_v)) ||
      !(previous_noise_w >= 0.0 && std::isfinite(previous_noise_w)))
    return core::invalid(why, "previous_noise_v/_w must be finite and >= 0");
  if (slip_drives < 1 || slip_drives > 20)
    return core::invalid(why, fmt::format("slip_drives = {} must be in 1..20", slip_drives));
  if (slip_stride < 1) return core::invalid(why, fmt::format("slip_stride = {} must be >= 1", slip_stride));
  if (threads < 1) return core::invalid(why, fmt::format("threads = {} must be >= 1", threads));
  return true;
}

void check_learned_scenarios(const LearnedStudyScenarios& s) {
  check_role(s.learn, "learn", false, false, false, false);
  check_role(s.eval, "eval", false, false, false, false);
  check_role(s.step, "step", false, false, true, true);
  check_role(s.slip, "slip", true, true, false, false);
  check_role(s.slip_eval, "slip_eval", true, true, true, false);
}

learned::FusionInput slice_fusion_input(const learned::FusionInput& in, std::size_t first) {
  if (first == 0 || first + 1 > in.size())
    throw std::invalid_argument(
        fmt::format("track '{}': cannot take steps {}.. of {}: fewer than 2 steps remain", in.track_name, first,
                    in.size()));
  learned::FusionInput out = in;
  const std::size_t from = first - 1;
  for (std::vector<double>* v : {&out.t, &out.dticks_l, &out.dticks_r, &out.v_kin, &out.w_kin, &out.power_l,
                                 &out.power_r, &out.v_ext, &out.w_ext, &out.v_ext_var, &out.w_ext_var,
                                 &out.gyro_z, &out.gt_x, &out.gt_y, &out.gt_theta, &out.v_true, &out.w_true})
    if (!v->empty()) v->erase(v->begin(), v->begin() + static_cast<std::ptrdiff_t>(std::min(from, v->size())));
  // Step 0 has no interval (fusion_input.h).
  for (std::vector<double>* v :
       {&out.dticks_l, &out.dticks_r, &out.v_kin, &out.w_kin, &out.v_true, &out.w_true})
    if (!v->empty()) (*v)[0] = 0.0;
  for (std::vector<double>* v :
       {&out.power_l, &out.power_r, &out.v_ext, &out.w_ext, &out.v_ext_var, &out.w_ext_var, &out.gyro_z})
    if (!v->empty()) (*v)[0] = kNaN;
  return out;
}

std::vector<double> slice_series(const std::vector<double>& v, std::size_t first) {
  if (first == 0 || first > v.size()) return v;
  std::vector<double> out(v.begin() + static_cast<std::ptrdiff_t>(first - 1), v.end());
  out[0] = 0.0;
  return out;
}

learned::OdometryErrors odometry_only_errors(const learned::FusionInput& in,
                                             const learned::OdometrySeries& odo) {
  return learned::odometry_errors(in, odo.v, odo.w, {}, {}, {});
}

std::vector<double> abs_errors(const std::vector<double>& est, const std::vector<double>& truth) {
  std::vector<double> out(est.size(), kNaN);
  for (std::size_t k = 0; k < est.size() && k < truth.size(); ++k)
    if (std::isfinite(est[k]) && std::isfinite(truth[k])) out[k] = std::abs(est[k] - truth[k]);
  return out;
}

double mean_squared_error(const std::vector<double>& est, const std::vector<double>& truth) {
  const learned::SeriesErrors e = learned::series_errors(est, truth, {});
  return e.samples > 0 ? e.rmse * e.rmse : kNaN;
}

LearnedStudy run_learned_study(const LearnedStudyScenarios& scenarios, const LearnedStudyOptions& options,
                               const LearnedStudyProgress& progress) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("study learned: " + why);
  check_learned_scenarios(scenarios);
  const auto t0 = std::chrono::steady_clock::now();
  Stage stage{progress, stage_count(options)};

  LearnedStudy out;
  out.options = options;
  learned::FusionInputOptions fo;
  fo.rate_hz = options.rate_hz;
  std::vector<sim::SlipEpisode> slip_eval_episodes;
  const std::vector<learned::FusionInput> inputs = simulate_roles(scenarios, options, fo, stage, out,
                                                                  slip_eval_episodes);
  const learned::FusionInput &learn = inputs[0], &eval = inputs[1], &step = inputs[2], &slip_eval = inputs[4];
  const std::vector<learned::FusionInput> extra = simulate_extra_slip_drives(scenarios, options, fo, stage,
                                                                             out);
  std::vector<const learned::FusionInput*> slips = {&inputs[3]};
  for (const learned::FusionInput& in : extra) slips.push_back(&in);

  train_velocity_nets(learn, options, stage, out);
  std::vector<learned::OdometrySeries> slip_lstm, slip_kin;
  train_detector(slips, options, stage, out, slip_lstm, slip_kin);
  set_static_variances(slips, slip_lstm, slip_kin, scenarios.slip.name, out);
  table1(eval, stage, out);
  table2(step, scenarios.step, options, stage, out);
  table3(slip_eval, slip_eval_episodes, options, stage, out);
  stage.finish();
  out.wall_s = seconds_since(t0);
  return out;
}

}  // namespace odotune::studies
