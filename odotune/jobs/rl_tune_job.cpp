// run_rl_tune (odotune/jobs/rl_job.h): the search, its scores and the written files
// (their text: rl_tune_text.cpp).
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <odotune/core/atomic_file.h>
#include <odotune/core/failure.h>
#include <odotune/core/output_paths.h>
#include <odotune/core/why.h>
#include <odotune/jobs/rl_job.h>

namespace odotune::jobs {

void write_tuned_params(const std::filesystem::path& path, const rlnode::RlParams& params,
                        const rlnode::ReplaySettings& tuned,
                        const std::optional<rlnode::GpsAlignment>& alignment, double fit_s, bool ros2,
                        std::string header) {
  rlnode::RlParamsUpdate update;
  update.process_noise_covariance = tuned.process_noise;
  if (tuned.filter == filters::rl::RlFilterType::ukf) update.ukf = tuned.ukf;
  if (alignment) {
    update.navsat_yaw_offset = alignment->yaw_offset_rad;
    header += fmt::format(
        "navsat_transform_node: the GPS-to-odom rotation was fitted on the first {:.0f} s ({:.4f} rad, residual "
        "{:.2f} m);\n  yaw_offset {:.4f} rad gives it with this IMU's heading at the first fix.\n",
        fit_s, alignment->transform.rotation_rad, alignment->rms_m, alignment->yaw_offset_rad);
  }
  bool advice = false;
  for (std::size_t s = 0; s < params.sensors.size(); ++s) {
    const double f = tuned.covariance_scale[s];
    if (std::abs(std::log10(f)) < 0.05) continue;
    if (!advice)
      header +=
          "Advised input covariances (the node reads them from the messages, so set them at the source):\n";
    advice = true;
    header += fmt::format(
        "  {} ({}): multiply its message covariance by {:.3g} (standard deviations by {:.3g})\n",
        params.sensors[s].name, params.sensors[s].topic, f, std::sqrt(f));
  }
  try {
    core::write_atomically(path, "parameter file",
                           rlnode::write_rl_params(params.file, params, update, ros2, header));
  } catch (const std::invalid_argument& e) {
    throw core::Failure(e.what());
  }
}

bool RlTuneRequest::IsValid(std::string* why) const {
  if (!SolverSettings::IsValid(why) || !options.IsValid(why) || !search.IsValid(why)) return false;
  if (until_s && from_s)
    return core::invalid(why, "--until and --from: expected one of them (tune before or after)");
  if (until_s && !(*until_s > 0.0))
    return core::invalid(why, fmt::format("--until {}: expected a positive number of seconds", *until_s));
  if (from_s && !(*from_s > 0.0))
    return core::invalid(why, fmt::format("--from {}: expected a positive number of seconds", *from_s));
  if (end_s && !(*end_s > until_s.value_or(from_s.value_or(0.0))))
    return core::invalid(why, fmt::format("--end {}: expected more seconds than --until or --from", *end_s));
  if (starts < 1 || starts > 1000)
    return core::invalid(why, fmt::format("--starts {}: expected 1 to 1000", starts));
  if (from_s && !(lead_in_s > 0.0 && lead_in_s < *from_s))
    return core::invalid(why, fmt::format("judging before --from {} s: a lead-in of {} s, expected (0, {})",
                                          *from_s, lead_in_s, *from_s));
  return true;
}

namespace {

constexpr std::int64_t kForever = std::numeric_limits<std::int64_t>::max();

// The span the tune's objective uses, on the recording it replays.
std::int64_t tuning_until_ns(const rlnode::Recording& rec, const RlTuneRequest& r) {
  if (r.until_s) return rl_time_ns(rec, *r.until_s);
  return r.end_s ? rl_time_ns(rec, *r.end_s) : kForever;
}

// The judged span on the whole recording: after --until, or before --from.
std::optional<RlJudgedSpan> judged_span(const rlnode::Recording& rec, const RlTuneRequest& r) {
  const std::int64_t end = r.end_s ? rl_time_ns(rec, *r.end_s) : kForever;
  if (r.until_s) {
    const std::int64_t until = rl_time_ns(rec, *r.until_s);
    if (until >= std::min(rec.end_ns, end)) return std::nullopt;
    return RlJudgedSpan{until, until, end};
  }
  if (r.from_s) return RlJudgedSpan{rl_time_ns(rec, r.lead_in_s), rec.start_ns, rl_time_ns(rec, *r.from_s)};
  return std::nullopt;
}

objectives::RlObjective make_objective(const rlnode::Recording& rec, const RlTuneRequest& r) {
  objectives::RlTuneOptions options = r.options;
  options.until_ns = tuning_until_ns(rec, r);
  try {
    return objectives::RlObjective(rec, rlnode::settings_of(rec.params), options);
  } catch (const std::invalid_argument& e) {
    throw core::Failure(e.what());
  }
}

// Progress over the whole search: each stage's count added to those before it.
SolverSettings stage_settings(const RlTuneRequest& r, std::uint64_t seed, long before, long total) {
  SolverSettings s = r;
  s.seed = seed;
  if (r.progress) s.progress = [p = r.progress, before, total](long done, long) { p(before + done, total); };
  return s;
}

// The evaluations of one profile (for progress).
long profile_budget(const objectives::RlObjective& objective, const RlTuneRequest& r) {
  if (!r.search.profile) return 0;
  long n = 0;
  const auto [lo, hi] = objective.bounds();
  for (std::size_t i = 0; i < lo.size(); ++i)
    n += static_cast<long>((hi[i] - lo[i]) / r.search.profile_step_decades) + 2;
  return n;
}

// The evaluations a start costs (for progress): the solver's budget, the profile's points, a few more.
long start_budget(const objectives::RlObjective& objective, const RlTuneRequest& r) {
  const long n = r.search.refine_decades > 0.0
                     ? (r.solver.kind == tuner::SolverChoice::Kind::pso
                            ? static_cast<long>(r.particles) * (r.iterations + 1)
                            : (r.evaluations > 0 ? r.evaluations
                                                 : static_cast<long>(r.particles) * (r.iterations + 1)))
                     : 0;
  return n + profile_budget(objective, r) + 2;
}

RlStartOutcome start_outcome(const objectives::RlObjective& objective, const RlStartResult& s) {
  RlStartOutcome o;
  o.seed = s.seed;
  o.factors = objective.space().to_physical(s.x);
  o.tuned = objective.settings_at(s.x);
  o.fitness = s.fitness;
  o.heldout = objective.heldout_score(o.tuned);
  o.outage = objective.outage_score(o.tuned);
  o.profiles = s.profiles;
  o.evaluations = s.evaluations;
  o.seconds = s.seconds;
  return o;
}

// The written start's run as one solver summary: the grid's result, then its
// refinement's log; every stage's evaluations and time.
tuner::Summary combined_summary(const RlGridResult& grid, const RlStartResult& s) {
  tuner::Summary sum = s.refinement;
  sum.log.clear();
  sum.log.push_back({0, grid.evaluations, grid.fitness});
  for (tuner::LogRecord rec : s.refinement.log) {
    rec.evaluations += grid.evaluations;
    rec.best_fitness = std::min(rec.best_fitness, grid.fitness);
    sum.log.push_back(rec);
  }
  sum.evaluations = grid.evaluations + s.evaluations;
  sum.seconds = grid.seconds + s.seconds;
  if (s.refinement.log.empty()) sum.termination = tuner::Termination::max_evaluations;
  sum.best_x = s.x;
  sum.best_fitness = s.fitness;
  return sum;
}

}  // namespace

RlTuneOutcome search_rl(const objectives::RlObjective& objective, const RlTuneRequest& request) {
  RlTuneOutcome o;
  for (const objectives::ParamSpec& p : objective.space().params()) o.param_names.push_back(p.name);
  o.outage_windows = objective.window_count();
  o.baseline_fitness = objective.baseline_fitness();
  o.baseline_heldout = objective.baseline_heldout();
  o.baseline_outage = objective.baseline_outage();
  const long per_start = start_budget(objective, request);
  // The grid's points and its profile, then each start; corrected by what the grid took.
  const long grid_count = rl_grid_points(objective, request.search) + profile_budget(objective, request);
  long total = per_start * request.starts + grid_count;
  o.grid = rl_grid_stage(objective, request.search, stage_settings(request, request.seed, 0, total));
  total += o.grid.evaluations - grid_count;
  std::vector<RlStartResult> runs;
  for (int k = 0; k < request.starts; ++k) {
    if (request.stop && request.stop->load()) break;
    const SolverSettings s = stage_settings(request, request.seed + static_cast<std::uint64_t>(k),
                                            o.grid.evaluations + k * per_start, total);
    runs.push_back(rl_refine_and_profile(objective, o.grid, request.search, s));
    o.starts.push_back(start_outcome(objective, runs.back()));
  }
  if (o.starts.empty()) throw core::Failure("tune: stopped before the first start");
  for (std::size_t k = 1; k < o.starts.size(); ++k)
    if (o.starts[k].fitness < o.starts[o.written].fitness) o.written = k;
  const RlStartOutcome& w = o.starts[o.written];
  o.factors = w.factors;
  o.tuned = w.tuned;
  o.tuned_fitness = w.fitness;
  o.tuned_heldout = w.heldout;
  o.tuned_outage = w.outage;
  o.summary = combined_summary(o.grid, runs[o.written]);
  o.diverged = objective.diverged();
  return o;
}

RlTuneOutcome tune_rl(const RlLoaded& loaded, const RlTuneRequest& request, const RlLoaded* tuned_on) {
  const rlnode::Recording& rec = loaded.rec;
  const rlnode::Recording& trec = tuned_on ? tuned_on->rec : rec;
  const objectives::RlObjective objective = make_objective(trec, request);
  RlTuneOutcome o = search_rl(objective, request);
  o.bag = rec.bag;
  o.params_file = rec.params.file;
  o.filter = rec.params.filter;
  o.duration_s = rl_seconds(rec, rec.end_ns);
  o.span_from_s = rl_seconds(rec, trec.start_ns);
  o.span_until_s = rl_seconds(rec, std::min(trec.end_ns, objective.options().until_ns));
  o.alignment = loaded.alignment;
  o.notes = trec.notes;
  if (tuned_on && tuned_on->alignment) {
    o.notes.push_back(
        fmt::format("the tune's replay (the bag from {:.1f} s) fitted navsat's rotation on its own "
                    "first {:.0f} s: {:.4f} rad (residual {:.2f} m)",
                    o.span_from_s, request.src.gps_heading_fit_s, tuned_on->alignment->transform.rotation_rad,
                    tuned_on->alignment->rms_m));
  }
  o.baseline = rlnode::settings_of(trec.params);
  o.judged = judged_span(rec, request);
  if (o.judged) {
    // The file's and every start's settings on the whole recording's judged
    // span, which the tune never saw.
    o.judged_from_s = rl_seconds(rec, std::min(o.judged->outage_from_ns, o.judged->fifth_from_ns));
    o.judged_until_s = rl_seconds(rec, std::min(rec.end_ns, o.judged->end_ns));
    o.baseline_judged = objectives::score_protocols(rec, rlnode::settings_of(rec.params), *o.judged);
    for (RlStartOutcome& start : o.starts)
      start.judged = objectives::score_protocols(rec, start.tuned, *o.judged);
    o.tuned_judged = o.starts[o.written].judged;
  }
  return o;
}

RlTuneOutcome run_rl_tune(const RlTuneRequest& request) {
  std::string why;
  if (!request.IsValid(&why)) throw core::Failure("tune: " + why);
  core::check_output_file("--config-out", request.config_out.string());
  core::check_output_file("--json", request.json_out.string());
  core::check_output_file("--config-out-ros1", request.config_out_ros1.string());
  if (!request.starts_out.empty()) core::check_output_dir("--starts-out", request.starts_out.string());
  const RlLoaded loaded = load_rl(request.src);
  const rlnode::Recording& rec = loaded.rec;
  std::optional<RlLoaded> after;
  if (request.from_s) {
    RlSource cut = request.src;
    cut.from_s = *request.from_s;
    after = load_rl(cut);
  }
  RlTuneOutcome o = tune_rl(loaded, request, after ? &*after : nullptr);
  const double fit_s = request.src.gps_heading_fit_s;
  for (const auto& [path, ros2] :
       {std::pair{request.config_out, !request.ros1_out}, std::pair{request.config_out_ros1, false}}) {
    if (!path.empty())
      write_tuned_params(path, rec.params, o.tuned, o.alignment, fit_s, ros2,
                         rl_tune_header(request, o, o.written));
  }
  if (!request.starts_out.empty()) {
    std::filesystem::create_directories(request.starts_out);
    for (std::size_t k = 0; k < o.starts.size(); ++k) {
      const auto path = request.starts_out / fmt::format("{}-seed{}.yaml",
                                                         filters::rl::to_string(o.starts[k].tuned.filter),
                                                         o.starts[k].seed);
      write_tuned_params(path, rec.params, o.starts[k].tuned, o.alignment, fit_s, !request.ros1_out,
                         rl_tune_header(request, o, k));
    }
  }
  if (!request.json_out.empty()) write_rl_tune_json(request.json_out, request, o);
  return o;
}

}  // namespace odotune::jobs
