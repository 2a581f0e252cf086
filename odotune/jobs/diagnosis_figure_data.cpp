#include <odotune/jobs/diagnosis_figure_data.h>

#include <cmath>

#include <odotune/diagnose/window_replay.h>

namespace odotune::jobs {
namespace {

using namespace odotune::diagnose;

std::vector<double> error_norm(const ResidualSeries& s) {
  std::vector<double> e(s.t_s.size());
  for (std::size_t i = 0; i < e.size(); ++i) e[i] = std::hypot(s.ex_m[i], s.ey_m[i]);
  return e;
}

std::string condition_label(Condition c) {
  switch (c) {
    case Condition::speed: return "speed v [m/s]";
    case Condition::turn_rate: return "turn rate |w| [rad/s]";
    case Condition::turn_speed: return "|v*w| [m/s^2]";
    case Condition::acceleration: return "|acceleration| [m/s^2]";
    case Condition::x: return "x [m]";
    case Condition::y: return "y [m]";
    case Condition::time: return "time since start [s]";
  }
  return "";
}

results::TrajectoryPath path(const std::string& name, const ReplayResult& r) {
  return {name, r.pred_x_m, r.pred_y_m};
}

}  // namespace

results::DiagnosisFigureData diagnosis_figure_data(const DiagInput& in, const Diagnosis& d,
                                                   const std::string& finding_text) {
  results::DiagnosisFigureData f;
  f.track = d.track;
  f.finding = finding_text;
  const bool found = !d.findings.empty();

  f.t_s = d.before.t_s;
  f.before_pos_err_m = error_norm(d.before);
  if (found) f.after_pos_err_m = error_norm(d.after);
  const std::vector<TimeSegment>& segs = !d.located_before.segments.empty() || !found
                                             ? d.located_before.segments
                                             : d.findings.front().segments;
  for (const TimeSegment& s : segs) f.segments.push_back({s.t0_s, s.t1_s});
  for (const Window& w : make_windows(in, d.window_s)) f.window_starts_s.push_back(w.t_begin_s);

  if (!d.located_before.conditions.empty()) {
    const Condition c = d.located_before.conditions.front().condition;
    f.condition_label = condition_label(c);
    f.residual_label = "residual growth / its noise sigma";
    for (std::size_t i = 0; i < d.before.t_s.size(); ++i)
      f.condition_value.push_back(condition_value(d.before, c, i));
    f.before_residual = d.located_before.z;
    if (found) f.after_residual = d.located_after.z;
  }

  f.ref_x_m = d.before.x_m, f.ref_y_m = d.before.y_m;
  f.flagged = d.located_before.flagged;
  for (const MapRegion& r : d.located_before.regions) f.regions.push_back({r.x0_m, r.x1_m, r.y0_m, r.y1_m});
  for (const Finding& g : d.findings)
    for (const MapRegion& r : g.regions) f.regions.push_back({r.x0_m, r.x1_m, r.y0_m, r.y1_m});
  if (d.model.on(Effect::slip_zone)) {
    const EffectSet& m = d.model;
    f.regions.push_back({m.get(Effect::slip_zone, "x0"), m.get(Effect::slip_zone, "x1"),
                         m.get(Effect::slip_zone, "y0"), m.get(Effect::slip_zone, "y1")});
  }

  f.overlay.push_back({in.reference == ReferenceKind::gt ? "ground truth" : "position fixes", in.ref_x_m,
                       in.ref_y_m});
  f.overlay.push_back(path("nominal model", replay(in, EffectSet{}, 0.0)));
  if (found) f.overlay.push_back(path("with the findings", replay(in, d.model, 0.0)));
  return f;
}

}  // namespace odotune::jobs
