#include <odotune/sim/slip_episodes.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include <odotune/core/why.h>

namespace odotune::sim {

namespace {

constexpr double kMaxStrength = 0.9;  // s in (0, 0.9]: some grip/rotation always remains

std::size_t wheel_index(SlipEpisode::Wheel w) { return w == SlipEpisode::Wheel::left ? 0 : 1; }

bool valid_kind(SlipEpisode::Kind k) { return k == SlipEpisode::Kind::spin || k == SlipEpisode::Kind::hold; }
bool valid_wheel(SlipEpisode::Wheel w) {
  return w == SlipEpisode::Wheel::left || w == SlipEpisode::Wheel::right;
}

std::string_view trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}

std::optional<double> to_number(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double x = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return x;
}

// One "KIND:key=value,..." part; `index` is 1-based, for messages.
SlipEpisode parse_part(std::string_view part, std::size_t index) {
  auto fail = [&](const std::string& msg) -> SlipEpisode {
    throw std::invalid_argument(fmt::format("slip episode {} '{}': {}", index, part, msg));
  };
  const auto colon = part.find(':');
  const std::string_view kind = trim(part.substr(0, colon));
  SlipEpisode e;
  if (kind == "spin") {
    e.kind = SlipEpisode::Kind::spin;
  } else if (kind == "hold") {
    e.kind = SlipEpisode::Kind::hold;
  } else {
    return fail(fmt::format("kind '{}' is unknown; expected spin or hold", kind));
  }
  if (colon == std::string_view::npos)
    return fail("no parameters; expected KIND:wheel=left|right,t0_s=..,t1_s=..,s=..[,ramp_s=..]");
  std::vector<std::string> seen;
  std::string_view rest = part.substr(colon + 1);
  while (true) {
    const auto comma = rest.find(',');
    const std::string_view item = trim(rest.substr(0, comma));
    const auto eq = item.find('=');
    if (eq == std::string_view::npos) return fail(fmt::format("'{}' is not KEY=VALUE", item));
    const std::string key(trim(item.substr(0, eq)));
    const std::string_view value = trim(item.substr(eq + 1));
    if (std::find(seen.begin(), seen.end(), key) != seen.end()) return fail(fmt::format("{} given twice", key));
    seen.push_back(key);
    if (key == "wheel") {
      if (value == "left")
        e.wheel = SlipEpisode::Wheel::left;
      else if (value == "right")
        e.wheel = SlipEpisode::Wheel::right;
      else
        return fail(fmt::format("wheel = '{}'; expected left or right", value));
    } else {
      double* target = key == "t0_s"                                            ? &e.t0_s
                       : key == "t1_s"                                          ? &e.t1_s
                       : key == "s"                                             ? &e.s
                       : key == "ramp_s"                                        ? &e.ramp_s
                       : key == "brake_nm" && e.kind == SlipEpisode::Kind::hold ? &e.brake_nm
                                                                                : nullptr;
      if (!target)
        return fail(fmt::format("unknown key '{}'; expected wheel, t0_s, t1_s, s, ramp_s{}", key,
                                e.kind == SlipEpisode::Kind::hold ? ", brake_nm" : " (brake_nm: hold only)"));
      const auto x = to_number(value);
      if (!x) return fail(fmt::format("{} = '{}' is not a number", key, value));
      *target = *x;
    }
    if (comma == std::string_view::npos) break;
    rest = rest.substr(comma + 1);
  }
  for (const char* required : {"wheel", "t0_s", "t1_s", "s"})
    if (std::find(seen.begin(), seen.end(), required) == seen.end())
      return fail(fmt::format("missing {}; expected wheel, t0_s, t1_s and s", required));
  return e;
}

}  // namespace

std::string_view kind_name(SlipEpisode::Kind kind) { return kind == SlipEpisode::Kind::hold ? "hold" : "spin"; }
std::string_view wheel_name(SlipEpisode::Wheel wheel) {
  return wheel == SlipEpisode::Wheel::right ? "right" : "left";
}

bool check_slip_episode(const SlipEpisode& e, std::string* field, std::string* why) {
  // The field at fault (for the caller's file:line) and the reason.
  auto invalid_field = [&](const char* f, std::string msg) {
    if (field) *field = f;
    return core::invalid(why, std::move(msg));
  };
  if (!valid_kind(e.kind))
    return invalid_field("kind", fmt::format("kind = {}; expected spin or hold", static_cast<int>(e.kind)));
  if (!valid_wheel(e.wheel))
    return invalid_field("wheel", fmt::format("wheel = {}; expected left or right", static_cast<int>(e.wheel)));
  if (!(std::isfinite(e.t0_s) && e.t0_s >= 0.0))
    return invalid_field("t0_s", fmt::format("t0_s = {}; expected a start time >= 0 s", e.t0_s));
  if (!(std::isfinite(e.t1_s) && e.t1_s > e.t0_s))
    return invalid_field("t1_s", fmt::format("t1_s = {}; expected an end time > t0_s = {} s", e.t1_s, e.t0_s));
  if (!(std::isfinite(e.s) && e.s > 0.0 && e.s <= kMaxStrength))
    return invalid_field("s", fmt::format("s = {}; expected a strength in (0, {}]", e.s, kMaxStrength));
  if (!(std::isfinite(e.ramp_s) && e.ramp_s > 0.0))
    return invalid_field("ramp_s", fmt::format("ramp_s = {}; expected a ramp duration > 0 s (0 would make the "
                                               "wheel's rate jump)",
                                               e.ramp_s));
  if (!(2.0 * e.ramp_s <= e.t1_s - e.t0_s))
    return invalid_field("ramp_s",
                         fmt::format("ramp_s = {}: the two ramps do not fit in [t0_s, t1_s] = [{}, {}] s; "
                                     "expected 2*ramp_s <= t1_s - t0_s = {} s",
                                     e.ramp_s, e.t0_s, e.t1_s, e.t1_s - e.t0_s));
  if (e.kind == SlipEpisode::Kind::hold && !(std::isfinite(e.brake_nm) && e.brake_nm >= 0.0))
    return invalid_field("brake_nm", fmt::format("brake_nm = {}; expected a braking torque >= 0 N*m (0: "
                                                 "2*robot.coulomb_friction_nm)",
                                                 e.brake_nm));
  if (e.kind == SlipEpisode::Kind::spin && e.brake_nm != 0.0)
    return invalid_field("brake_nm",
                         fmt::format("brake_nm = {} on a spin episode; expected 0 (brake_nm applies "
                                     "to hold episodes only)",
                                     e.brake_nm));
  return true;
}

bool validate_slip_episodes(const std::vector<SlipEpisode>& episodes, std::string* why) {
  if (episodes.size() > kMaxSlipEpisodes)
    return core::invalid(why, fmt::format("slip_episodes: {} episodes; expected at most {}", episodes.size(),
                                          kMaxSlipEpisodes));
  for (std::size_t i = 0; i < episodes.size(); ++i) {
    std::string field, msg;
    if (!check_slip_episode(episodes[i], &field, &msg))
      return core::invalid(why, fmt::format("slip_episodes[{}]: {}", i + 1, msg));
  }
  // Per wheel, in order of start: an episode starting before the latest end
  // so far overlaps the episode owning that end.
  for (const auto wheel : {SlipEpisode::Wheel::left, SlipEpisode::Wheel::right}) {
    std::vector<std::size_t> idx;
    for (std::size_t i = 0; i < episodes.size(); ++i)
      if (episodes[i].wheel == wheel) idx.push_back(i);
    std::stable_sort(idx.begin(), idx.end(),
                     [&](std::size_t a, std::size_t b) { return episodes[a].t0_s < episodes[b].t0_s; });
    std::size_t owner = 0;
    bool have = false;
    for (const std::size_t i : idx) {
      const SlipEpisode& e = episodes[i];
      if (have && e.t0_s < episodes[owner].t1_s) {
        const std::size_t a = std::max(i, owner), b = std::min(i, owner);
        const SlipEpisode& ea = episodes[a];
        const SlipEpisode& eb = episodes[b];
        return core::invalid(
            why, fmt::format("slip_episodes[{}] ([{}, {}] s) overlaps slip_episodes[{}]{} ([{}, {}] s) on the "
                             "{} wheel; expected episodes on the same wheel not to overlap in time",
                             a + 1, ea.t0_s, ea.t1_s, b + 1,
                             eb.line > 0 ? fmt::format(" (line {})", eb.line) : std::string(), eb.t0_s, eb.t1_s,
                             wheel_name(wheel)));
      }
      if (!have || e.t1_s > episodes[owner].t1_s) owner = i;
      have = true;
    }
  }
  return true;
}

double episode_strength(const SlipEpisode& e, double t_s) {
  if (!(t_s > e.t0_s && t_s < e.t1_s)) return 0.0;
  const double up = (t_s - e.t0_s) / e.ramp_s, down = (e.t1_s - t_s) / e.ramp_s;
  return e.s * std::min({1.0, up, down});
}

double slip_strength(const std::vector<SlipEpisode>& episodes, double t_s, SlipEpisode::Wheel wheel) {
  double s = 0.0;
  for (const SlipEpisode& e : episodes)
    if (e.wheel == wheel) s = std::max(s, episode_strength(e, t_s));
  return s;
}

bool slipping(const std::vector<SlipEpisode>& episodes, double t_s) {
  return std::any_of(episodes.begin(), episodes.end(),
                     [t_s](const SlipEpisode& e) { return episode_strength(e, t_s) > 0.0; });
}

std::string format_slip_episodes(const std::vector<SlipEpisode>& episodes) {
  std::string out;
  for (const SlipEpisode& e : episodes) {
    out += fmt::format("{}{}:wheel={},t0_s={},t1_s={},s={},ramp_s={}", out.empty() ? "" : "; ",
                       kind_name(e.kind), wheel_name(e.wheel), e.t0_s, e.t1_s, e.s, e.ramp_s);
    if (e.kind == SlipEpisode::Kind::hold) out += fmt::format(",brake_nm={}", e.brake_nm);
  }
  return out.empty() ? "none" : out;
}

std::vector<SlipEpisode> parse_slip_episodes(std::string_view text) {
  text = trim(text);
  std::vector<SlipEpisode> out;
  if (text.empty() || text == "none") return out;
  std::size_t index = 1;
  while (true) {
    const auto semi = text.find(';');
    const std::string_view part = trim(text.substr(0, semi));
    if (part.empty())
      throw std::invalid_argument(
          fmt::format("slip episode {}: empty; expected KIND:wheel=..,t0_s=..,t1_s=..,s=.. "
                      "between '; ' separators",
                      index));
    if (out.size() >= kMaxSlipEpisodes)
      throw std::invalid_argument(fmt::format("slip episodes: more than {}; expected at most {}",
                                              kMaxSlipEpisodes, kMaxSlipEpisodes));
    out.push_back(parse_part(part, index++));
    if (semi == std::string_view::npos) break;
    text = text.substr(semi + 1);
  }
  std::string why;
  if (!validate_slip_episodes(out, &why)) throw std::invalid_argument(why);
  return out;
}

std::vector<SlipEpisode> slip_episodes_from_metadata(const tracks::TrackMeta& meta) {
  const auto text = meta.get("sim.slip_episodes");
  if (!text) return {};
  try {
    return parse_slip_episodes(*text);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(fmt::format("sim.slip_episodes: {}", e.what()));
  }
}

SlipSchedule::SlipSchedule(const std::vector<SlipEpisode>& episodes) {
  for (const SlipEpisode& e : episodes) by_wheel_[wheel_index(e.wheel)].push_back(e);
  for (auto& list : by_wheel_)
    std::stable_sort(list.begin(), list.end(),
                     [](const SlipEpisode& a, const SlipEpisode& b) { return a.t0_s < b.t0_s; });
}

SlipSchedule::Active SlipSchedule::at(double t_s, SlipEpisode::Wheel wheel) const {
  const auto& list = by_wheel_[wheel_index(wheel)];
  // The last episode starting before t_s is the only one that can act (no
  // overlaps on one wheel).
  const auto it = std::lower_bound(list.begin(), list.end(), t_s,
                                   [](const SlipEpisode& e, double t) { return e.t0_s < t; });
  if (it == list.begin()) return {};
  const SlipEpisode& e = *std::prev(it);
  const double s = episode_strength(e, t_s);
  return s > 0.0 ? Active{&e, s} : Active{};
}

}  // namespace odotune::sim
