#include <odotune/diagnose/reconcile.h>

#include <cmath>
#include <initializer_list>

#include <fmt/format.h>

namespace odotune::diagnose {
namespace {

// z beyond which a lag estimate counts as flagged (as the ratio checks' default z_threshold).
constexpr double kLagZ = 4.0;

const Finding* carried_by(const Diagnosis& d, std::initializer_list<Effect> effects) {
  for (const Finding& f : d.findings)
    for (Effect e : effects)
      if (f.is(e)) return &f;
  return nullptr;
}

// Why `e` is not a finding: its materiality line, else the last selection
// record that tried it, else that it was not a candidate here.
std::string why_not(const Diagnosis& d, Effect e) {
  const std::string name(effect_name(e));
  for (const ImmaterialEffect& s : d.immaterial)
    if (s.effect == e) return fmt::format("{} was significant but immaterial ({})", name, s.line);
  const auto& recs = d.selection.records;
  for (auto it = recs.rbegin(); it != recs.rend(); ++it) {
    if (it->phase != "forward" || it->effects != std::vector<Effect>{e}) continue;
    if (it->reason.rfind("not the best", 0) == 0)
      for (const SearchRecord& r : recs)  // the step's best, and why it was rejected or accepted
        if (r.phase == "forward" && r.step == it->step && r.reason.rfind("best candidate", 0) == 0)
          return fmt::format(
              "{} was tried but {} predicted held-out windows better (CV {:.4g} vs {:.4g}), and {}", name,
              r.candidate, r.cv_score, it->cv_score,
              r.accepted ? "was chosen" : "was itself rejected: " + r.reason.substr(r.reason.find(':') + 2));
    return fmt::format("{} was tried and not chosen ({})", name, it->reason);
  }
  if (!d.selection.note.empty()) return fmt::format("no effect was selected ({})", d.selection.note);
  return fmt::format("{} was not a candidate for this odometry and reference", name);
}

void ratio_line(const Diagnosis& d, const Verdict& v, const char* what, std::initializer_list<Effect> carriers,
                Effect main, std::vector<std::string>& out) {
  if (!v.departs()) return;
  const std::string head = fmt::format("{} {:.3f} (z = {:.1f})", what, v.value, v.z);
  if (const Finding* f = carried_by(d, carriers)) {
    out.push_back(fmt::format("{}: carried by {}", head, f->name()));
    return;
  }
  out.push_back(fmt::format("{} is not a finding: {}", head, why_not(d, main)));
}

void lag_line(const Diagnosis& d, const LagEstimate& l, const char* what,
              std::initializer_list<Effect> carriers, Effect main, std::vector<std::string>& out) {
  if (!l.available || !(std::abs(l.lag_s) > kLagZ * l.std_error_s)) return;
  const std::string head = fmt::format("{} {:.3f} ± {:.3f} s", what, l.lag_s, l.std_error_s);
  if (const Finding* f = carried_by(d, carriers)) {
    out.push_back(fmt::format("{}: carried by {}", head, f->name()));
    return;
  }
  out.push_back(fmt::format("{} is not a finding: {}", head, why_not(d, main)));
}

}  // namespace

std::vector<std::string> reconcile_sensor_checks(const Diagnosis& d) {
  std::vector<std::string> out;
  const OdometryCheck& o = d.sensors.odometry;
  if (o.available) {
    ratio_line(d, o.speed_ratio, "speed ratio (reference / odometry)",
               {Effect::radius_error, Effect::speed_radius, Effect::odometry_bias, Effect::longitudinal_slip,
                Effect::radius_step, Effect::slip_zone},
               Effect::radius_error, out);
    ratio_line(d, o.yaw_ratio, "yaw-rate ratio (reference / odometry)",
               {Effect::wheel_base_error, Effect::radius_error, Effect::odometry_bias, Effect::radius_step},
               Effect::wheel_base_error, out);
    lag_line(d, o.odometry_late, "odometry late against the reference by",
             {Effect::time_offset, Effect::actuator_lag}, Effect::time_offset, out);
    lag_line(d, o.command_delay, "motion late against the commands by",
             {Effect::actuator_lag, Effect::time_offset}, Effect::actuator_lag, out);
  }
  const GyroCheck& g = d.has_gyro_fixes ? d.gyro_fixes.gyro : d.sensors.gyro;
  if (g.available) {
    ratio_line(d, g.bias, "gyro bias [rad/s]", {Effect::gyro_bias}, Effect::gyro_bias, out);
    ratio_line(d, g.scale, "gyro scale", {Effect::gyro_scale}, Effect::gyro_scale, out);
  }
  return out;
}

}  // namespace odotune::diagnose
