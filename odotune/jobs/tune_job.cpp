#include <odotune/jobs/tune_job.h>

#include <stdexcept>

#include <odotune/tuner/nlopt_solver.h>
#include <odotune/tuner/problem.h>
#include <odotune/tuner/pso.h>

namespace odotune::jobs {

PreparedTrack prepare_track(const tracks::Track& track) {
  PreparedTrack p;
  p.name = track.name();
  p.input = objectives::build_replay_input(track);
  if (p.input.fixes.empty())
    throw std::invalid_argument(
        "track '" + track.name() +
        "': no position fixes (aps_x, aps_y), so the EKF has nothing to correct with and its "
        "noise cannot matter; add fixes made from ground truth with `odotune fixes`");
  p.fast = std::make_unique<objectives::FastReplay>(p.input);
  return p;
}

PreparedTrack prepare_track_fix_cv(const tracks::Track& track, const objectives::FixCvOptions& cv) {
  objectives::ReplayInputOptions o;
  o.reference = objectives::ReplayReference::fixes;
  objectives::ReplayInput from_fix = objectives::build_replay_input(track, o);
  PreparedTrack p;
  if (track.has_gt()) {
    p = prepare_track(track);
  } else {
    p.name = track.name();
    p.input = from_fix;
  }
  p.cv = std::make_unique<objectives::FixCvReplay>(from_fix, cv);
  return p;
}

bool SolverSettings::IsValid(std::string* why) const {
  if (solver.kind == tuner::SolverChoice::Kind::pso) {
    tuner::PsoOptions o;
    o.particles = particles;
    o.iterations = iterations;
    return o.IsValid(why);
  }
  tuner::NloptOptions o;
  o.algorithm = solver.nlopt_algorithm;
  o.max_evaluations = evaluations > 0 ? evaluations : 1;
  return o.IsValid(why);
}

objectives::ErrorMetrics mean_metrics(const std::vector<objectives::ErrorMetrics>& per_track) {
  objectives::ErrorMetrics m;
  for (const auto& t : per_track) {
    m.rmse_m += t.rmse_m;
    m.mae_m += t.mae_m;
    m.maxe_m += t.maxe_m;
    m.samples += t.samples;
  }
  const double n = per_track.empty() ? 1.0 : static_cast<double>(per_track.size());
  m.rmse_m /= n;
  m.mae_m /= n;
  m.maxe_m /= n;
  return m;
}

tuner::Summary run_solver(tuner::ProblemRef problem, const SolverSettings& s, std::vector<double> x0) {
  tuner::Summary summary;
  if (s.solver.kind == tuner::SolverChoice::Kind::pso) {
    tuner::PsoOptions o;
    o.particles = s.particles;
    o.iterations = s.iterations;
    o.seed = s.seed;
    o.progress = s.progress;
    o.stop = s.stop;
    summary = tuner::pso_minimize(problem, o);
  } else {
    tuner::NloptOptions o;
    o.algorithm = s.solver.nlopt_algorithm;
    o.max_evaluations = s.evaluations > 0 ? s.evaluations : static_cast<long>(s.particles) * (s.iterations + 1);
    o.seed = s.seed;
    if (!x0.empty()) o.x0 = std::move(x0);
    o.progress = s.progress;
    o.stop = s.stop;
    summary = tuner::nlopt_minimize(problem, o);
  }
  if (!summary.ok() || summary.best_x.empty())
    throw std::runtime_error("solver " + s.solver.name() + ": " + summary.termination_text());
  return summary;
}

DefaultsTune run_solver_from_defaults(tuner::ProblemRef problem, const SolverSettings& s,
                                      const objectives::BoxSpace& space,
                                      const std::vector<double>& default_params) {
  DefaultsTune t;
  for (const auto& p : space.params()) {
    t.param_names.push_back(p.name);
    t.param_units.push_back(p.unit);
  }
  const std::vector<double> default_x = space.to_box(default_params);
  t.summary = run_solver(problem, s, default_x);
  // The baseline's fitness by the same problem (an objective counts this
  // evaluation like any other, but the solver's summary does not).
  t.baseline_fitness = problem.fitness(default_x);
  t.default_kept = t.baseline_fitness < t.summary.best_fitness;
  t.tuned_fitness = t.default_kept ? t.baseline_fitness : t.summary.best_fitness;
  t.params = t.default_kept ? default_params : space.to_physical(t.summary.best_x);
  return t;
}

namespace {

// Runs the solver on `objective` and fills the outcome's request, summary,
// tuned parameters (names, units, physical values, noise) and divergences.
TuneOutcome solve(const objectives::EkfObjective& objective, const TuneRequest& request) {
  const BoxProblem<objectives::EkfObjective> problem{&objective};
  TuneOutcome out;
  out.request = request;
  out.summary = run_solver(problem, request);
  const objectives::ParamSpace& space = objective.space();
  for (const auto& p : space.params()) {
    out.param_names.push_back(p.name);
    out.param_units.push_back(p.unit);
  }
  out.params = space.to_physical(out.summary.best_x);
  out.noise = space.to_noise(out.params);
  out.divergences = objective.divergences();
  return out;
}

// Modes 8 and 9: the same tune over the fix cross-validation replays; scores
// are the held-out fixes' (and, where the track has it, ground truth's).
TuneOutcome run_tune_fix_cv(const std::vector<const PreparedTrack*>& tracks, const TuneRequest& request) {
  std::vector<const objectives::FixCvReplay*> cv;
  for (const auto* t : tracks) {
    if (!t->cv)
      throw std::invalid_argument("track '" + t->name +
                                  "': not prepared for fix cross-validation (modes 8, 9)");
    cv.push_back(t->cv.get());
  }
  TuneOutcome out = solve(objectives::EkfObjective::over_fixes(cv, request.model, request.mode), request);
  out.against_fixes = true;
  out.fix_cv = tracks.front()->cv->options();
  std::vector<objectives::ErrorMetrics> base, tuned;
  for (const auto* t : tracks) {
    TrackScore s;
    s.track = t->name;
    const objectives::FixCvOutcome b = t->cv->evaluate(objectives::baseline_noise()),
                                   u = t->cv->evaluate(out.noise);
    s.baseline = b.heldout;
    s.tuned = u.heldout;
    s.baseline_nll = b.nll;
    s.tuned_nll = u.nll;
    s.baseline_nis = b.nis;
    s.tuned_nis = u.nis;
    if (!t->input.reference_is_fixes) {
      s.gt_baseline = objectives::replay_ekf(t->input, objectives::baseline_noise()).outcome.metrics;
      s.gt_tuned = objectives::replay_ekf(t->input, out.noise).outcome.metrics;
    }
    const double n = static_cast<double>(tracks.size());
    out.baseline_fitness += objectives::fix_cv_fitness(b, request.mode) / n;
    out.tuned_fitness += objectives::fix_cv_fitness(u, request.mode) / n;
    base.push_back(s.baseline);
    tuned.push_back(s.tuned);
    out.tracks.push_back(std::move(s));
  }
  out.baseline_mean = mean_metrics(base);
  out.tuned_mean = mean_metrics(tuned);
  return out;
}

}  // namespace

TuneOutcome run_tune(const std::vector<const PreparedTrack*>& tracks, const TuneRequest& request) {
  std::string why;
  if (!request.IsValid(&why)) throw std::invalid_argument(why);
  if (tracks.empty()) throw std::invalid_argument("no tracks to tune on");
  if (objectives::is_fix_cv(request.mode)) return run_tune_fix_cv(tracks, request);
  std::vector<const objectives::FastReplay*> fast;
  for (const auto* t : tracks) {
    if (!t->fast || t->input.reference_is_fixes)
      throw std::invalid_argument("track '" + t->name + "': mode " +
                                  std::to_string(objectives::number(request.mode)) +
                                  " needs ground truth; tracks without it are tuned with modes 8 and 9");
    fast.push_back(t->fast.get());
  }
  TuneOutcome out = solve(objectives::EkfObjective(fast, request.model, request.mode), request);

  // Scores from the reference replay, independent of the fast path.
  std::vector<objectives::ErrorMetrics> base, tuned;
  for (const auto* t : tracks) {
    TrackScore s;
    s.track = t->name;
    s.baseline = objectives::replay_ekf(t->input, objectives::baseline_noise()).outcome.metrics;
    s.tuned = objectives::replay_ekf(t->input, out.noise).outcome.metrics;
    base.push_back(s.baseline);
    tuned.push_back(s.tuned);
    out.tracks.push_back(s);
  }
  out.baseline_mean = mean_metrics(base);
  out.tuned_mean = mean_metrics(tuned);
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    out.baseline_fitness += objectives::fitness_of(base[i], request.mode) / static_cast<double>(tracks.size());
    out.tuned_fitness += objectives::fitness_of(tuned[i], request.mode) / static_cast<double>(tracks.size());
  }
  return out;
}

}  // namespace odotune::jobs
