#include <odotune/cli/tune_output.h>

#include <fmt/format.h>

#include <odotune/cli/output.h>
#include <odotune/jobs/calibration_tune_json.h>

namespace odotune::cli {

namespace {

// "track1, track2": the tracks a tune ran on (each score names its track).
template <class Scores>
std::string track_names(const Scores& tracks) {
  std::string names;
  for (const auto& t : tracks) names += (names.empty() ? "" : ", ") + t.track;
  return names;
}

}  // namespace

void print_tune_outcome(const jobs::TuneOutcome& o) {
  const std::string names = track_names(o.tracks);
  if (!o.note.empty()) fmt::print("{}\n", o.note);
  fmt::print("tuned {} noise on {} for mode {} ({}) with {} (seed {})\n", filters::to_string(o.request.model),
             names, objectives::number(o.request.mode), objectives::fitness_mode_name(o.request.mode),
             o.request.solver.name(), o.request.seed);
  if (o.against_fixes) {
    const objectives::FixCvOptions& cv = o.fix_cv;
    fmt::print("  held-out fixes ({} folds of {:g} s blocks), baseline → tuned:\n", cv.folds, cv.block_s);
    for (const auto& t : o.tracks)
      fmt::print("    {}: NLL {:.3f} → {:.3f} nats per fix; NIS {:.2f} → {:.2f} (2 when consistent)\n", t.track,
                 t.baseline_nll, t.tuned_nll, t.baseline_nis, t.tuned_nis);
  }
  print_tune_result(o.baseline_mean, o.tuned_mean, o.tracks, o.param_names, o.params, o.summary,
                    o.divergences.total());
  if (o.against_fixes)
    for (const auto& t : o.tracks)
      if (t.gt_baseline && t.gt_tuned)
        fmt::print("  {} against its ground truth (never seen by the tune): RMSE {}\n", t.track,
                   metric_change(t.gt_baseline->rmse_m, t.gt_tuned->rmse_m));
}

void print_tune_outcome(const jobs::CalibrationTuneOutcome& o) {
  const jobs::CalibrationTuneRequest& r = o.request;
  const std::string names = track_names(o.baseline.tracks);
  fmt::print("tuned the {} calibrator's settings on {} with {} (seed {}); resampler {}, policy {}, "
             "calibrator seed {}\n",
             objectives::to_string(objectives::TunedModel::calibration(r.model)), names, r.solver.name(),
             r.seed, filters::to_string(o.default_pf.resampler), filters::to_string(o.default_pf.policy),
             o.default_pf.seed);
  fmt::print("  score (lower is better): {:.4g} with the paper's defaults → {:.4g} tuned{}\n", o.baseline_score,
             o.tuned_score, o.default_kept ? " (the defaults scored best: kept)" : "");
  fmt::print("  calibrated odometry, dead-reckoning position error:\n");
  fmt::print("    RMSE {}\n", metric_change(o.baseline_mean.rmse_m, o.tuned_mean.rmse_m));
  fmt::print("    MAE  {}\n", metric_change(o.baseline_mean.mae_m, o.tuned_mean.mae_m));
  fmt::print("    MAXE {}\n", metric_change(o.baseline_mean.maxe_m, o.tuned_mean.maxe_m));
  for (std::size_t k = 0; k < o.baseline.tracks.size() && k < o.tuned.tracks.size(); ++k) {
    const auto& b = o.baseline.tracks[k];
    const auto& t = o.tuned.tracks[k];
    const auto eb = jobs::radius_error_pct(b.calibration), et = jobs::radius_error_pct(t.calibration);
    fmt::print("    {}: RMSE {}; {} → {}", b.track, metric_change(b.errors.rmse_m, t.errors.rmse_m),
               jobs::convergence_text(b.calibration), jobs::convergence_text(t.calibration));
    if (eb && et) fmt::print("; final radius error {:.3f} → {:.3f} %", *eb, *et);
    fmt::print("\n");
  }
  fmt::print("  mean particles per iteration: {:.0f} → {:.0f}\n", o.baseline.mean_particles,
             o.tuned.mean_particles);
  fmt::print("  settings:\n");
  for (std::size_t i = 0; i < o.params.size(); ++i)
    fmt::print("    {:<28} {:>12.6g}  (default {:.6g}) [{}]\n", o.param_names[i], o.params[i],
               o.default_params[i], o.param_units[i]);
  fmt::print("  {} evaluations in {:.2f} s ({}); failed evaluations: {}\n", o.summary.evaluations,
             o.summary.seconds, o.summary.termination_text(), o.failures);
}

void print_tune_outcome(const jobs::UkfTuneOutcome& o) {
  const jobs::UkfTuneRequest& r = o.request;
  const std::string names = track_names(o.tracks);
  fmt::print("tuned the fusion UKF's noise on {} for mode {} ({}) with {} (seed {})\n", names,
             objectives::number(r.mode), objectives::fitness_mode_name(r.mode), r.solver.name(), r.seed);
  fmt::print("  fused pose vs ground truth, defaults → tuned{}\n",
             o.default_kept ? " (the defaults scored best and are kept)" : "");
  print_tune_result(o.baseline_mean, o.tuned_mean, o.tracks, o.param_names, o.params, o.summary, o.failures);
}

}  // namespace odotune::cli
