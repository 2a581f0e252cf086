#include <odotune/sim/motion_profile.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

namespace odotune::sim {

namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kShrink = 0.95;    // cruise lowering factor per try
constexpr double kMinScale = 1e-3;  // give up below this cruise fraction
constexpr double kTimeTol = 1e-12;  // [s]

const char* kind_name(Segment::Kind k) {
  switch (k) {
    case Segment::Kind::straight: return "straight";
    case Segment::Kind::arc: return "arc";
    case Segment::Kind::spin: return "spin";
    case Segment::Kind::stop: return "stop";
  }
  return "?";
}

[[noreturn]] void bad_field(const Segment& s, std::size_t i, const char* field, double value,
                            const char* expected) {
  throw ProfileError(i, fmt::format("segment {} ({}): {} = {}; expected {}", i + 1, kind_name(s.kind), field,
                                    value, expected));
}

void need_positive(const Segment& s, std::size_t i, const char* field, double value) {
  if (!(std::isfinite(value) && value > 0.0)) bad_field(s, i, field, value, "a number > 0");
}

void need_nonzero(const Segment& s, std::size_t i, const char* field, double value) {
  if (!(std::isfinite(value) && value != 0.0)) bad_field(s, i, field, value, "a non-zero number");
}

// The knots path (file comment of motion_profile.h): checked, copied as given.
std::vector<MotionProfile::Knot> checked_knots(const std::vector<VelocityKnot>& in) {
  std::vector<MotionProfile::Knot> out;
  out.reserve(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    const VelocityKnot& k = in[i];
    auto bad = [&](const char* field, double value, const std::string& expected) {
      throw ProfileError(i, fmt::format("knot {}: {} = {}; expected {}", i + 1, field, value, expected));
    };
    if (!std::isfinite(k.t_s)) bad("t_s", k.t_s, "a finite number");
    if (!std::isfinite(k.v_m_s)) bad("v_m_s", k.v_m_s, "a finite number");
    if (!std::isfinite(k.w_rad_s)) bad("w_rad_s", k.w_rad_s, "a finite number");
    if (i == 0 && k.t_s != 0.0) bad("t_s", k.t_s, "0 for the first knot");
    if (i > 0 && !(k.t_s > in[i - 1].t_s))
      bad("t_s", k.t_s, fmt::format("a time > {} (the previous knot's; strictly increasing)", in[i - 1].t_s));
    out.push_back({k.t_s, k.v_m_s, k.w_rad_s});
  }
  return out;
}

double ramp_s(const Command& a, const Command& b, double max_acc, double max_ang_acc) {
  return std::max(std::abs(a.v_m_s - b.v_m_s) / max_acc, std::abs(a.w_rad_s - b.w_rad_s) / max_ang_acc);
}

}  // namespace

Cruise segment_cruise(const Segment& s, std::size_t i) {
  switch (s.kind) {
    case Segment::Kind::straight:
      need_nonzero(s, i, "distance_m", s.distance_m);
      need_positive(s, i, "speed_m_s", s.speed_m_s);
      return {std::copysign(s.speed_m_s, s.distance_m), 0.0, std::abs(s.distance_m) / s.speed_m_s};
    case Segment::Kind::arc: {
      need_positive(s, i, "radius_m", s.radius_m);
      need_nonzero(s, i, "angle_deg", s.angle_deg);
      need_positive(s, i, "speed_m_s", s.speed_m_s);
      const double w = std::copysign(s.speed_m_s / s.radius_m, s.angle_deg);
      return {s.speed_m_s, w, std::abs(s.angle_deg) * kDegToRad * s.radius_m / s.speed_m_s};
    }
    case Segment::Kind::spin:
      need_nonzero(s, i, "angle_deg", s.angle_deg);
      need_positive(s, i, "rate_deg_s", s.rate_deg_s);
      return {0.0, std::copysign(s.rate_deg_s * kDegToRad, s.angle_deg), std::abs(s.angle_deg) / s.rate_deg_s};
    case Segment::Kind::stop:
      if (!(std::isfinite(s.duration_s) && s.duration_s >= 0.0))
        bad_field(s, i, "duration_s", s.duration_s, "a number >= 0");
      return {0.0, 0.0, s.duration_s};
  }
  throw ProfileError(i, fmt::format("segment {}: unknown kind", i + 1));
}

namespace {

// The segments' cruise commands, each scaled down where the segment is too
// short for its transitions (file comment of motion_profile.h).
class CruisePlan {
 public:
  CruisePlan(const std::vector<Segment>& segs, double acc, double ang)
      : segs_(segs), n_(segs.size()), acc_(acc), ang_(ang), base_(n_), scale_(n_, 1.0) {
    for (std::size_t i = 0; i < n_; ++i) base_[i] = segment_cruise(segs_[i], i);
  }

  std::size_t size() const { return n_; }
  double scale(std::size_t i) const { return scale_[i]; }

  Command cruise(std::ptrdiff_t i) const {  // rest outside [0, n)
    if (i < 0 || i >= static_cast<std::ptrdiff_t>(n_)) return {};
    const auto k = static_cast<std::size_t>(i);
    return {base_[k].v_m_s * scale_[k], base_[k].w_rad_s * scale_[k]};
  }
  // Transition j is between segment j-1 and segment j (j = 0..n).
  double ramp(std::size_t j) const {
    const auto sj = static_cast<std::ptrdiff_t>(j);
    return ramp_s(cruise(sj - 1), cruise(sj), acc_, ang_);
  }

  // Lowers the cruise of segments too short for their transitions.
  void fit_scales() {
    for (int sweep = 0; sweep < 50; ++sweep) {
      bool changed = false;
      for (std::size_t i = 0; i < n_; ++i) {
        if (is_stop(i)) continue;
        while (!fits(i)) {
          scale_[i] *= kShrink;
          changed = true;
          if (scale_[i] < kMinScale)
            throw ProfileError(i, fmt::format("segment {} ({}) is too short for the acceleration "
                                              "limits even at {:.1f} % of its speed",
                                              i + 1, kind_name(segs_[i].kind), 100.0 * kMinScale));
        }
      }
      if (!changed) break;
    }
    for (std::size_t i = 0; i < n_; ++i)
      if (!is_stop(i) && !fits(i))
        throw ProfileError(i, fmt::format("segment {} ({}): no cruise speed fits the acceleration "
                                          "limits between its neighbours",
                                          i + 1, kind_name(segs_[i].kind)));
  }

  // Timeline of transition centres b_j (j = 0..n).
  std::vector<double> transition_centres() const {
    std::vector<double> b(n_ + 1);
    b[0] = 0.5 * ramp(0);
    for (std::size_t i = 0; i < n_; ++i) {
      const double d = is_stop(i) ? base_[i].duration_s + 0.5 * (ramp(i) + ramp(i + 1))
                                  : base_[i].duration_s / scale_[i];
      b[i + 1] = b[i] + d;
    }
    return b;
  }

 private:
  bool is_stop(std::size_t i) const { return segs_[i].kind == Segment::Kind::stop; }
  bool fits(std::size_t i) const {
    return base_[i].duration_s / scale_[i] + kTimeTol >= 0.5 * (ramp(i) + ramp(i + 1));
  }

  const std::vector<Segment>& segs_;
  std::size_t n_;
  double acc_, ang_;
  std::vector<Cruise> base_;
  std::vector<double> scale_;
};

void add_knot(std::vector<MotionProfile::Knot>& knots, double t, Command c) {
  if (!knots.empty()) {
    const MotionProfile::Knot& last = knots.back();
    const bool same = last.v_m_s == c.v_m_s && last.w_rad_s == c.w_rad_s;
    if (t <= last.t_s + kTimeTol && same) return;
    if (same && knots.size() >= 2 && knots[knots.size() - 2].v_m_s == c.v_m_s &&
        knots[knots.size() - 2].w_rad_s == c.w_rad_s) {
      knots.back().t_s = t;  // extend a constant stretch instead of adding a knot
      return;
    }
    t = std::max(t, last.t_s);
  }
  knots.push_back({t, c.v_m_s, c.w_rad_s});
}

// The knots: each transition's ramp, centred on b_j, from the cruise before
// to the cruise after; starting at t = 0.
std::vector<MotionProfile::Knot> plan_knots(const CruisePlan& plan, const std::vector<double>& b) {
  std::vector<MotionProfile::Knot> knots;
  for (std::size_t j = 0; j <= plan.size(); ++j) {
    const auto sj = static_cast<std::ptrdiff_t>(j);
    const double half = 0.5 * plan.ramp(j);
    add_knot(knots, b[j] - half, plan.cruise(sj - 1));
    add_knot(knots, b[j] + half, plan.cruise(sj));
  }
  if (knots.front().t_s != 0.0) knots.insert(knots.begin(), MotionProfile::Knot{0.0, 0.0, 0.0});
  return knots;
}

}  // namespace

MotionProfile::MotionProfile(const MotionParams& motion) {
  const double acc = motion.max_accel_m_s2;
  const double ang = motion.max_angular_accel_rad_s2;
  if (!(std::isfinite(acc) && acc > 0.0))
    throw ProfileError(ProfileError::npos, fmt::format("max_accel_m_s2 = {}; expected a number > 0", acc));
  if (!(std::isfinite(ang) && ang > 0.0))
    throw ProfileError(ProfileError::npos,
                       fmt::format("max_angular_accel_rad_s2 = {}; expected a number > 0", ang));
  if (!motion.knots.empty()) {
    if (!motion.segments.empty())
      throw ProfileError(ProfileError::npos,
                         "segments and knots both given; expected one of them (segments: planned "
                         "motion, knots: an explicit velocity profile)");
    knots_ = checked_knots(motion.knots);
    return;
  }
  const std::size_t n = motion.segments.size();
  if (n == 0) return;

  CruisePlan plan(motion.segments, acc, ang);
  plan.fit_scales();
  const std::vector<double> b = plan.transition_centres();
  knots_ = plan_knots(plan, b);
  plan_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Command c = plan.cruise(static_cast<std::ptrdiff_t>(i));
    plan_[i] = {c.v_m_s, c.w_rad_s, plan.scale(i), b[i], b[i + 1]};
  }
}

Command MotionProfile::at(double t_s) const {
  if (knots_.empty() || !(t_s > knots_.front().t_s) || !(t_s < knots_.back().t_s)) {
    if (knots_.empty()) return {};
    const Knot& k = t_s >= knots_.back().t_s ? knots_.back() : knots_.front();
    return {k.v_m_s, k.w_rad_s};
  }
  const auto it = std::upper_bound(knots_.begin(), knots_.end(), t_s,
                                   [](double t, const Knot& k) { return t < k.t_s; });
  const Knot& hi = *it;
  const Knot& lo = *(it - 1);
  const double span = hi.t_s - lo.t_s;
  if (!(span > 0.0)) return {hi.v_m_s, hi.w_rad_s};
  const double a = (t_s - lo.t_s) / span;
  return {lo.v_m_s + a * (hi.v_m_s - lo.v_m_s), lo.w_rad_s + a * (hi.w_rad_s - lo.w_rad_s)};
}

}  // namespace odotune::sim
