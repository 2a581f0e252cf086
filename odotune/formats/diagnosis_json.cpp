#include <odotune/formats/diagnosis_json.h>

#include <cmath>

#include <odotune/sim/model_terms.h>

namespace odotune::formats {
namespace {

using nlohmann::json;
using namespace odotune::diagnose;

json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json before_after(const BeforeAfter& s) {
  return {{"before_pos_rmse_m", number(s.before_pos_rmse_m)}, {"after_pos_rmse_m", number(s.after_pos_rmse_m)}};
}

json segments(const std::vector<TimeSegment>& segs) {
  json a = json::array();
  for (const TimeSegment& s : segs) a.push_back({s.t0_s, s.t1_s});
  return a;
}

json regions(const std::vector<MapRegion>& regs) {
  json a = json::array();
  for (const MapRegion& r : regs) a.push_back({r.x0_m, r.x1_m, r.y0_m, r.y1_m});
  return a;
}

json named(const std::vector<NamedValue>& values) {
  json o = json::object();
  for (const NamedValue& v : values) o[v.name] = number(v.value);
  return o;
}

json verdict(const Verdict& v) {
  return {{"value", number(v.value)},
          {"stderr", number(v.std_error)},
          {"noop", v.noop},
          {"z", number(v.z)},
          {"drift", number(v.drift)},
          {"noise_drift", number(v.noise_drift)},
          {"significant", v.significant},
          {"relevant", v.relevant},
          {"departs", v.departs()}};
}

json lag(const LagEstimate& l) {
  if (!l.available) return nullptr;
  return {{"lag_s", number(l.lag_s)},
          {"stderr_s", number(l.std_error_s)},
          {"peak_correlation", number(l.peak_correlation)},
          {"at_edge", l.at_edge}};
}

json sensor_checks(const SensorCheck& s) {
  json gyro = {{"available", s.gyro.available}};
  if (s.gyro.available) {
    gyro["bins"] = s.gyro.bins;
    gyro["noise_sigma_rad_s"] = number(s.gyro.noise_sigma_radps);
    gyro["gyro_scale.s"] = verdict(s.gyro.scale);
    gyro["gyro_bias.b"] = verdict(s.gyro.bias);
  } else {
    gyro["reason"] = s.gyro.unavailable_reason;
  }
  json odo = {{"available", s.odometry.available}};
  if (s.odometry.available) {
    odo["bins"] = s.odometry.bins;
    odo["speed_ratio"] = verdict(s.odometry.speed_ratio);
    odo["yaw_ratio"] = verdict(s.odometry.yaw_ratio);
    odo["odometry_late"] = lag(s.odometry.odometry_late);
    odo["command_delay"] = lag(s.odometry.command_delay);
  } else {
    odo["reason"] = s.odometry.unavailable_reason;
  }
  return {{"gyro", gyro}, {"odometry", odo}};
}

// The held-out recordings' verdict (recordings.h HeldoutTest).
json heldout_test(const diagnose::HeldoutTest& t) {
  return {{"before_pos_rmse_m", number(t.error.before_pos_rmse_m)},
          {"after_pos_rmse_m", number(t.error.after_pos_rmse_m)},
          {"floor_m", number(t.floor_m)},
          {"windows", t.windows},
          {"informative_windows", t.paired.changed},
          {"better_windows", t.paired.improved},
          {"p_rank", number(t.paired.p_rank)},
          {"p_t", number(t.paired.p_t)},
          {"p_stouffer", number(t.paired.p_param)},
          {"significant", t.paired.significant},
          {"material", t.material},
          {"proven", t.proven}};
}

json heldout_comparison(const HeldoutComparison& h) {
  return {{"windows", h.windows},
          {"informative", h.informative},
          {"improved", h.improved},
          {"before_pos_rmse_m", number(h.ref_pos_rmse_m)},
          {"after_pos_rmse_m", number(h.alt_pos_rmse_m)},
          {"z", number(h.z)},
          {"p", number(h.p)},
          {"passed", h.passed}};
}

// gyro_fixes_check.h: the gyro judged by dead reckoning against the fixes.
json gyro_vs_fixes(const GyroFixesCheck& g) {
  json o = {{"available", g.gyro.available}};
  if (!g.gyro.available) {
    o["reason"] = g.gyro.unavailable_reason;
    return o;
  }
  o["window_s"] = g.window_s;
  o["used_windows"] = g.used_windows;
  o["heldout_windows"] = g.heldout_windows;
  o["gyro_scale.s"] = verdict(g.gyro.scale);
  o["gyro_bias.b"] = verdict(g.gyro.bias);
  o["distance_scale"] = number(g.distance_scale);
  o["standstill_s"] = g.standstill_s;
  o["heldout"] = {{"joint", heldout_comparison(g.joint)},
                  {"gyro_scale.s", heldout_comparison(g.scale_own)},
                  {"gyro_bias.b", heldout_comparison(g.bias_own)}};
  return o;
}

json search_log(const Selection& s) {
  json a = json::array();
  for (const SearchRecord& r : s.records)
    a.push_back({{"phase", r.phase},
                 {"step", r.step},
                 {"candidate", r.candidate},
                 {"set", r.set},
                 {"cv_score", number(r.cv_score)},
                 {"rel_improvement", number(r.rel_improvement)},
                 {"p_rank", number(r.p_rank)},
                 {"p_t", number(r.p_t)},
                 {"delta_bic", number(r.delta_bic)},
                 {"accepted", r.accepted},
                 {"reason", r.reason}});
  return {{"folds", s.folds},
          {"folds_are_recordings", s.folds_are_recordings},
          {"windows", s.num_windows},
          {"baseline_cv_score", number(s.baseline_cv_score)},
          {"final_cv_score", number(s.final_cv_score)},
          {"records", a}};
}

// An unexplained finding's `model` (diagnosis-output.md): the formula, the
// terms (name as the spec writes it, the wheel speed it corrects, the
// coefficient's unit), the terms' own before/after fit, and whether they are
// proven on recordings the fit never saw (`proven`, `fit.heldout_recordings`).
json term_model(const TermModel& m) {
  json terms = json::array();
  for (const FoundTerm& t : m.terms)
    terms.push_back({{"name", t.name},
                     {"target", std::string(sim::target_name(t.term.target))},
                     {"coef", number(t.term.coef)},
                     {"stderr", number(t.std_error)},
                     {"unit", std::string(sim::coef_unit(t.term.basis))}});
  json out = {{"formula", m.formula},
              {"terms", terms},
              {"proven", m.proven},
              {"fit",
               {{"train",
                 {{"before_pos_rmse_m", number(m.train.before_pos_rmse_m)},
                  {"after_pos_rmse_m", number(m.train.after_pos_rmse_m)}}},
                {"heldout",
                 {{"before_pos_rmse_m", number(m.heldout.before_pos_rmse_m)},
                  {"after_pos_rmse_m", number(m.heldout.after_pos_rmse_m)}}}}}};
  if (m.other_recordings)
    out["fit"]["heldout_recordings"] = {{"before_pos_rmse_m", number(m.other_recordings->before_pos_rmse_m)},
                                        {"after_pos_rmse_m", number(m.other_recordings->after_pos_rmse_m)}};
  return out;
}

// The term search's log (term_search.h).
json term_search_log(const TermSearchResult& r) {
  json steps = json::array();
  for (const TermStep& s : r.steps)
    steps.push_back(
        {{"step", s.step}, {"added", s.added}, {"cv_score", number(s.cv_score)}, {"accepted", s.accepted}});
  return {{"found", r.found},
          {"library_size", r.library_size},
          {"floor_m", number(r.floor_m)},
          {"steps", steps},
          {"reason", r.reason}};
}

json effect_names(const std::vector<diagnose::Effect>& effects) {
  json out = json::array();
  for (diagnose::Effect e : effects) out.push_back(diagnose::effect_name(e));
  return out;
}

json immaterial_lines(const std::vector<ImmaterialEffect>& immaterial) {
  json out = json::array();
  for (const ImmaterialEffect& i : immaterial) out.push_back(i.line);
  return out;
}

}  // namespace

json diagnosis_json(const Diagnosis& d) {
  json findings = json::array();
  for (const Finding& f : d.findings) {
    findings.push_back(
        {{"effect", diagnose::to_string(f.kind)},
         {"params", named(f.params)},
         {"stderr", named(f.stderrs)},
         {"where",
          {{"segments", segments(f.segments)}, {"conditions", f.conditions}, {"regions", regions(f.regions)}}},
         {"explains", number(f.explains)},
         {"fit", {{"train", before_after(f.train)}, {"heldout", before_after(f.heldout)}}},
         {"rivals", effect_names(f.rivals)},
         {"discrete", f.discrete},
         {"evidence", f.evidence}});
    if (f.model) findings.back()["model"] = term_model(*f.model);
    if (f.heldout_test) findings.back()["fit"]["heldout_recordings_test"] = heldout_test(*f.heldout_test);
  }
  json model = json::array();
  for (const Finding& f : d.findings)
    if (!f.spec().empty()) model.push_back(f.spec());
  return {{"format", "odotune-diagnosis/1"},
          {"track", d.track},
          {"reference", d.reference == ReferenceKind::gt ? "gt" : "aps"},
          {"reference_samples",
           {{"gt", d.ref_gt_samples}, {"aps", d.ref_fix_samples}, {"heading", d.ref_heading}}},
          {"materiality", {{"floor_m", number(d.floor_m)}, {"immaterial", immaterial_lines(d.immaterial)},
                           {"not_reproduced", d.not_reproduced}, {"not_confirmed", d.not_confirmed}}},
          {"sensor_checks_reconciled", d.sensor_notes},
          {"replay", {{"window_s", d.window_s}}},
          {"baseline",
           {{"pos_rmse_m", number(d.baseline_pos_rmse_m)},
            {"heading_rmse_rad", number(d.baseline_heading_rmse_rad)}}},
          {"findings", findings},
          {"final",
           {{"pos_rmse_m", number(d.final_pos_rmse_m)},
            {"heading_rmse_rad", number(d.final_heading_rmse_rad)}}},
          {"train", before_after(d.train)},
          {"heldout", before_after(d.heldout)},
          {"split", {{"train_windows", d.train_windows},
                     {"heldout_windows", d.heldout_windows},
                     {"scored_against", d.scored_on_denoised_reference ? "denoised reference"
                                                                       : "reference"}}},
          {"model", model},
          {"located", {{"segments", segments(d.located_before.segments)},
                       {"regions", regions(d.located_before.regions)},
                       {"conditions", d.located_before.phrase}}},
          {"sensor_checks", d.has_gyro_fixes ? [&] {
             json j = sensor_checks(d.sensors);
             j["gyro_vs_fixes"] = gyro_vs_fixes(d.gyro_fixes);
             return j;
           }()
                                             : sensor_checks(d.sensors)},
          {"selection", search_log(d.selection)},
          {"term_search", term_search_log(d.term_search)},
          {"timing_s",
           {{"total", d.timing.total_s}, {"sensors", d.timing.sensors_s},
            {"select", d.timing.select_s}, {"locate", d.timing.locate_s}, {"terms", d.timing.terms_s}}},
          {"note", d.note}};
}

json pooled_diagnosis_json(const diagnose::PooledDiagnosis& p) {
  json j = diagnosis_json(p.pooled);
  json tracks = json::array();
  for (const diagnose::RecordingResult& r : p.recordings) {
    json refit = json::object(), refit_se = json::object();
    for (const NamedValue& v : r.refit) refit[v.name] = number(v.value);
    for (const NamedValue& v : r.refit_stderr) refit_se[v.name] = number(v.value);
    tracks.push_back({{"track", r.track},
                      {"role", r.heldout ? "heldout" : "fit"},
                      {"duration_s", number(r.duration_s)},
                      {"reference_samples", r.ref_samples},
                      {"ref_sigma_m", number(r.ref_sigma_m)},
                      {"error", before_after(r.error)},
                      {"floor_m", number(r.floor_m)},
                      {"helped", r.helped},
                      {"refit", refit},
                      {"refit_stderr", refit_se},
                      {"pooled_time_offset_s", number(r.pooled_time_offset_s)},
                      {"speed_ratio", number(r.speed_ratio)},
                      {"yaw_ratio", number(r.yaw_ratio)},
                      {"motion_late_s", number(r.motion_late_s)},
                      {"note", r.note}});
  }
  j["tracks"] = tracks;
  j["heldout_from"] = p.heldout_recordings ? "heldout recordings" : "pooled split";
  if (p.heldout_recordings) j["heldout_recordings_test"] = heldout_test(p.heldout_test);
  j["consistency"] = p.consistency;
  return j;
}

}  // namespace odotune::formats
