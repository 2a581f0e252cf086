#include <odotune/jobs/diagnose_job.h>

#include <exception>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/atomic_file.h>
#include <odotune/core/failure.h>
#include <odotune/diagnose/diag_input.h>
#include <odotune/diagnose/diagnosis_summary.h>
#include <odotune/formats/diagnosis_json.h>
#include <odotune/formats/scenario_yaml.h>
#include <odotune/jobs/diagnosis_figure_data.h>
#include <odotune/results/diagnosis_report.h>
#include <odotune/sim/scenario_from_track.h>
#include <odotune/tracks/track_io.h>

namespace odotune::jobs {

namespace {

// The scenario of --scenario-out: the track's robot with the findings'
// effects, driven along its reference path.
std::string corrected_scenario_yaml(const tracks::Track& track, const std::string& track_file,
                                    const diagnose::Diagnosis& d) {
  std::vector<std::string> specs;
  std::string names;
  for (const diagnose::Finding& f : d.findings)
    if (!f.spec().empty()) {
      specs.push_back(f.spec());
      names += (names.empty() ? "" : ", ") + std::string(f.name());
    }
  // Terms outside physics-effects.md (an unexplained finding's model): the
  // simulator replays them (odotune/sim/model_terms.h).
  std::vector<sim::ModelTerm> terms;
  for (const diagnose::Finding& f : d.findings)
    if (f.model) {
      for (const diagnose::FoundTerm& t : f.model->terms) terms.push_back(t.term);
      names += (names.empty() ? "" : ", ") + std::string("terms ") + f.model->formula;
    }
  try {
    sim::Scenario sc = sim::scenario_from_track(track, specs);
    sc.terms = terms;
    return formats::scenario_to_yaml(
        sc, fmt::format("The robot of track '{}' ({}) with the physics `odotune diagnose` found:\n"
                        "  {}\n"
                        "driven along the recording's reference path (motion.knots: its body\n"
                        "velocities, smoothed; simulated time 0 = the first reference sample).\n"
                        "Reproduce the corrected model:  odotune simulate THIS_FILE -o corrected.csv",
                        d.track, track_file, names.empty() ? "none (the nominal model explains it)" : names));
  } catch (const std::exception& e) {
    throw core::Failure(fmt::format("{}: cannot build the corrected scenario: {}", track_file, e.what()));
  }
}

}  // namespace

namespace {

// One recording as the diagnosis reads it, cut to [from_s, to_s] when asked.
diagnose::DiagInput diag_input(const DiagnoseRequest& a, const std::string& file, const tracks::Track& track) {
  try {
    diagnose::DiagInput in = diagnose::build_diag_input(track);
    // An open end of the interval is ±1e300 s, beyond any track's time.
    if (a.from_s || a.to_s) in = diagnose::crop(in, a.from_s.value_or(-1e300), a.to_s.value_or(1e300));
    return in;
  } catch (const std::invalid_argument& e) {
    throw core::Failure(fmt::format("{}: {}", file, e.what()));
  }
}

}  // namespace

DiagnoseOutcome run_diagnose(const DiagnoseRequest& a) {
  if (a.tracks.empty()) throw core::Failure("diagnose: no track given");
  const formats::ControllerOptions controller = check_controller_request(a.controller, false);
  std::vector<std::string> files = a.tracks;
  files.insert(files.end(), a.heldout.begin(), a.heldout.end());
  const std::vector<tracks::Track> tracks = tracks::load_tracks(files);
  const tracks::Track& track = tracks.front();
  std::vector<diagnose::DiagInput> inputs;
  for (std::size_t k = 0; k < tracks.size(); ++k) inputs.push_back(diag_input(a, files[k], tracks[k]));
  diagnose::DiagInput in = inputs.front();
  filters::OdometryParams nominal;
  if (!a.controller.out.empty()) nominal = diagnosis_track_nominal(in, files.front());
  diagnose::DiagnoseOptions o;
  o.select.fit.window_s = a.window_s;
  o.select.materiality = a.materiality;
  DiagnoseOutcome out;
  const diagnose::Diagnosis& d = out.diagnosis;
  out.several = files.size() > 1;
  try {
    if (out.several) {
      const std::vector<diagnose::DiagInput> fit(inputs.begin(),
                                                 inputs.begin() + static_cast<long>(a.tracks.size()));
      const std::vector<diagnose::DiagInput> held(inputs.begin() + static_cast<long>(a.tracks.size()),
                                                  inputs.end());
      out.pooled = diagnose::diagnose_recordings(fit, held, o);
      out.diagnosis = out.pooled.pooled;
      in = out.pooled.input;
    } else {
      out.diagnosis = diagnose::diagnose(in, o);
    }
  } catch (const std::invalid_argument& e) {
    throw core::Failure(fmt::format("{}: cannot diagnose: {}", files.front(), e.what()));
  }
  out.summary = out.several ? diagnose::pooled_summary(out.pooled) : diagnose::diagnosis_summary(d);
  const std::string json_text =
      (out.several ? formats::pooled_diagnosis_json(out.pooled) : formats::diagnosis_json(d)).dump(2) + "\n";
  if (!a.report.empty()) {
    std::string finding;  // the effects' names (the titles have room for no more)
    for (const diagnose::Finding& f : d.findings)
      finding += (finding.empty() ? "" : ", ") + std::string(f.name());
    try {
      results::write_diagnosis_report(a.report, diagnosis_figure_data(in, d, finding), out.summary, json_text);
    } catch (const std::exception& e) {
      throw core::Failure(fmt::format("{}: report: {}", a.report, e.what()));
    }
  }
  if (!a.scenario_out.empty())
    core::write_atomically(a.scenario_out, "scenario", corrected_scenario_yaml(track, files.front(), d));
  if (!a.controller.out.empty()) {
    const auto g = diagnosis_controller_geometry(d, out.several ? &out.pooled : nullptr, nominal, a.tracks,
                                                 a.heldout);
    out.controller_line = g ? write_controller_file(a.controller, controller, *g)
                            : fmt::format(
                                  "controller: no radius_error or wheel_base_error found; {} not written",
                                  a.controller.out);
  }
  if (!a.json.empty()) core::write_atomically(a.json, "diagnosis JSON", json_text);
  return out;
}

}  // namespace odotune::jobs
