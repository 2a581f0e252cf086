#include <odotune/jobs/simulate_job.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/failure.h>
#include <odotune/formats/scenario_yaml.h>
#include <odotune/sim/effects.h>
#include <odotune/sim/motion_profile.h>
#include <odotune/sim/random_slip.h>
#include <odotune/sim/simulator.h>
#include <odotune/tracks/track_io.h>

namespace odotune::jobs {

namespace {

std::uint64_t parse_seed(const char* flag, const std::string& text) {
  std::uint64_t seed = 0;
  const char* end = text.data() + text.size();
  const auto [p, ec] = std::from_chars(text.data(), end, seed);
  if (ec != std::errc() || p != end)
    throw core::Failure(fmt::format("{} {}: expected a non-negative integer below 2^64", flag, text));
  return seed;
}

// The scenario file with the request's overrides applied.
sim::Scenario scenario_of(const SimulateRequest& r) {
  sim::Scenario sc;
  try {
    sc = formats::load_scenario(r.scenario);
  } catch (const formats::ScenarioError& e) {
    throw core::Failure(e.what());
  }
  {
    std::error_code ec;
    if (std::filesystem::exists(r.output, ec) && std::filesystem::equivalent(r.output, r.scenario, ec))
      throw core::Failure(fmt::format("simulate: -o {} is the scenario file itself; expected a track file name",
                                      r.output));
  }
  if (!r.seed.empty()) sc.seed = parse_seed("--seed", r.seed);
  if (!r.random_slip.empty()) {
    const std::uint64_t layout = parse_seed("--random-slip", r.random_slip);
    try {
      sc.slip_episodes = sim::random_slip_episodes(sim::MotionProfile(sc.motion), layout);
    } catch (const std::exception& e) {  // the profile was validated with the scenario
      throw core::Failure(fmt::format("{}: --random-slip: {}", r.scenario, e.what()));
    }
    if (sc.slip_episodes.empty())
      throw core::Failure(
          fmt::format("{}: --random-slip {}: the drive has no stretch long and fast enough for a slip "
                      "episode (>= 2 s at >= 0.3 m/s); expected a longer drive",
                      r.scenario, r.random_slip));
  }
  if (r.no_effects) sc.effects = sim::Effects{};
  for (const auto& text : r.effects) {
    sim::EffectSpec spec;
    try {
      spec = sim::parse_effect_spec(text);
    } catch (const std::invalid_argument& e) {
      throw core::Failure(fmt::format("--{}", e.what()));  // "--effect 'TEXT': ..."
    }
    try {
      sim::apply_effect(sc.effects, spec);
    } catch (const std::invalid_argument& e) {
      throw core::Failure(fmt::format("--effect '{}': {}", text, e.what()));
    }
  }
  return sc;
}

}  // namespace

double path_length_m(const tracks::Track& track) {
  if (!track.has_gt()) return 0.0;
  const auto& x = track.col(tracks::Col::gt_x);
  const auto& y = track.col(tracks::Col::gt_y);
  double len = 0.0, px = 0.0, py = 0.0;
  bool have = false;
  for (std::size_t i = 0; i < track.size(); ++i) {
    if (std::isnan(x[i]) || std::isnan(y[i])) continue;
    if (have) len += std::hypot(x[i] - px, y[i] - py);
    px = x[i], py = y[i], have = true;
  }
  return len;
}

SimulateOutcome run_simulate(const SimulateRequest& r) {
  const sim::Scenario sc = scenario_of(r);
  const tracks::Track track = [&] {
    try {
      return sim::simulate(sc);
    } catch (const std::invalid_argument& e) {
      throw core::Failure(fmt::format("{}: {}", r.scenario, e.what()));
    }
  }();
  try {
    tracks::write_track(track, r.output);
  } catch (const std::exception& e) {
    throw core::Failure(e.what());
  }
  return {track.name(),           track.size(), track.duration_s(),
          path_length_m(track),   sc.seed,      sim::format_effects(sc.effects),
          sc.slip_episodes.size()};
}

}  // namespace odotune::jobs
