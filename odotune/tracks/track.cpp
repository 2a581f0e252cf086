#include <odotune/tracks/track.h>

#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/enum_names.h>

namespace odotune::tracks {

namespace {
constexpr std::array<std::string_view, kNumCols> kNames = {
    "omega_l",   "omega_r",   "v_cmd", "w_cmd", "gyro_z",    "power_l",   "power_r", "v_ext", "w_ext",
    "v_ext_var", "w_ext_var", "aps_x", "aps_y", "aps_var_x", "aps_var_y", "gt_x",    "gt_y",  "gt_theta"};
}  // namespace

std::string_view column_name(Col c) { return kNames[static_cast<std::size_t>(c)]; }

const std::vector<std::string_view>& known_column_names() {
  static const std::vector<std::string_view> names = [] {
    std::vector<std::string_view> v = {"t", "ticks_l", "ticks_r"};
    v.insert(v.end(), kNames.begin(), kNames.end());
    return v;
  }();
  return names;
}

std::string_view to_string(BodyVelocitySource s) {
  return s == BodyVelocitySource::commanded ? "commanded" : "measured";
}

bool parse_body_velocity_source(std::string_view text, BodyVelocitySource* out) {
  return core::parse_by_name(text, {BodyVelocitySource::commanded, BodyVelocitySource::measured}, out);
}

std::optional<std::string> TrackMeta::get(std::string_view key) const {
  for (const auto& [k, v] : extra)
    if (k == key) return v;
  return std::nullopt;
}

std::vector<double>& TrackData::ensure(Col c) {
  auto& v = col(c);
  if (v.empty()) v.assign(t.size(), std::numeric_limits<double>::quiet_NaN());
  return v;
}

Track::Track(TrackData data) : d_(std::move(data)) {
  const std::size_t n = d_.t.size();
  for (int c = 0; c < kNumCols; ++c) {
    const auto& v = d_.cols[static_cast<std::size_t>(c)];
    if (!v.empty() && v.size() != n)
      throw std::invalid_argument(fmt::format("track '{}': column {} has {} rows, t has {}", d_.meta.name,
                                              kNames[static_cast<std::size_t>(c)], v.size(), n));
  }
  if ((!d_.ticks_l.empty() && d_.ticks_l.size() != n) || (!d_.ticks_r.empty() && d_.ticks_r.size() != n))
    throw std::invalid_argument(fmt::format("track '{}': tick columns do not match t", d_.meta.name));
  for (std::size_t i = 1; i < n; ++i)
    if (!(d_.t[i] > d_.t[i - 1]))
      throw std::invalid_argument(fmt::format("track '{}': t not strictly increasing at row {}", d_.meta.name,
                                              i));
}

}  // namespace odotune::tracks
