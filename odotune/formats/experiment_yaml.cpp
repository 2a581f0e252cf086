#include <odotune/formats/experiment_yaml.h>

#include <glob.h>

#include <algorithm>
#include <fstream>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <odotune/core/failure.h>
#include <odotune/formats/yaml_error.h>
#include <odotune/objectives/metrics.h>

namespace odotune::formats {

namespace {

constexpr const char* kFormat = "odotune-experiment/1";

template <typename T>
T scalar(const std::filesystem::path& path, const YAML::Node& node, const char* what) {
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    fail_at(path, node,
            fmt::format("{} has a bad value, expected {}", what,
                        std::is_same_v<T, std::string> ? "text" : "a number"));
  }
}

std::vector<YAML::Node> list(const std::filesystem::path& path, const YAML::Node& root, const char* key) {
  const YAML::Node n = root[key];
  if (!n) fail_at(path, root, fmt::format("missing '{}'", key));
  if (!n.IsSequence() || n.size() == 0) fail_at(path, n, fmt::format("'{}' must be a non-empty list", key));
  return {n.begin(), n.end()};
}

std::vector<std::string> expand(const std::filesystem::path& path, const YAML::Node& node,
                                const std::filesystem::path& base) {
  const std::string pattern = scalar<std::string>(path, node, "a track");
  const std::filesystem::path full = std::filesystem::path(pattern).is_absolute()
                                         ? std::filesystem::path(pattern)
                                         : base / pattern;
  glob_t g{};
  const int rc = ::glob(full.c_str(), 0, nullptr, &g);
  std::vector<std::string> out;
  if (rc == 0)
    for (std::size_t i = 0; i < g.gl_pathc; ++i) out.emplace_back(g.gl_pathv[i]);
  globfree(&g);
  if (out.empty()) fail_at(path, node, fmt::format("no track file matches '{}'", full.string()));
  std::sort(out.begin(), out.end());
  return out;
}

void read_calibration(const std::filesystem::path& path, const YAML::Node& c, ExperimentCalibration* out) {
  if (!c.IsMap())
    fail_at(path, c, "calibration must be a mapping {resampler, policy, particles, seed, ext_from_gt_hz}");
  for (const auto& kv : c) {
    const auto key = kv.first.as<std::string>("");
    if (key == "resampler") {
      if (!filters::parse_resampler(scalar<std::string>(path, kv.second, "calibration.resampler"),
                                    &out->resampler))
        fail_at(path, kv.second,
                "calibration.resampler must be multinomial, stratified, systematic or residual");
    } else if (key == "policy") {
      if (!filters::parse_resample_policy(scalar<std::string>(path, kv.second, "calibration.policy"),
                                          &out->policy))
        fail_at(path, kv.second, "calibration.policy must be every, neff or max");
    } else if (key == "particles") {
      out->particles = scalar<int>(path, kv.second, "calibration.particles");
      if (out->particles < 0)
        fail_at(path, kv.second, "calibration.particles must be ≥ 1 (or 0 for the paper's count)");
    } else if (key == "seed") {
      out->seed = scalar<std::uint64_t>(path, kv.second, "calibration.seed");
    } else if (key == "ext_from_gt_hz") {
      out->ext_from_gt_hz = scalar<double>(path, kv.second, "calibration.ext_from_gt_hz");
      if (!(out->ext_from_gt_hz >= 0.0 && out->ext_from_gt_hz <= 1000.0))
        fail_at(path, kv.second, "calibration.ext_from_gt_hz must be 0 (off) or a rate in (0, 1000] Hz");
    } else {
      fail_at(path, kv.first,
              fmt::format("unknown calibration key '{}', expected resampler, policy, particles, seed "
                          "or ext_from_gt_hz",
                          key));
    }
  }
}

ExperimentRl read_rl(const std::filesystem::path& path, const YAML::Node& c,
                     const std::filesystem::path& base) {
  if (!c.IsMap()) fail_at(path, c, "robot_localization must be a mapping {params, until_s, ...}");
  ExperimentRl rl;
  bool has_params = false, has_until = false;
  for (const auto& kv : c) {
    const auto key = kv.first.as<std::string>("");
    const YAML::Node& v = kv.second;
    const std::string what = "robot_localization." + key;
    if (key == "params") {
      rl.params = base / scalar<std::string>(path, v, what.c_str());
      has_params = true;
    } else if (key == "node_name") {
      rl.node_name = scalar<std::string>(path, v, what.c_str());
    } else if (key == "gps_topic") {
      rl.gps_topic = scalar<std::string>(path, v, what.c_str());
    } else if (key == "navsat_params") {
      rl.navsat_params = base / scalar<std::string>(path, v, what.c_str());
    } else if (key == "remap") {
      if (!v.IsSequence()) fail_at(path, v, "robot_localization.remap must be a list of FROM=TO");
      for (const auto& t : v)
        rl.remap.push_back(scalar<std::string>(path, t, "a robot_localization.remap entry"));
    } else if (key == "tf") {
      if (!v.IsSequence())
        fail_at(path, v, "robot_localization.tf must be a list of FRAME=x,y,z,roll,pitch,yaw");
      for (const auto& t : v) rl.tf.push_back(scalar<std::string>(path, t, "a robot_localization.tf entry"));
    } else if (key == "gps_heading_fit_s") {
      rl.gps_heading_fit_s = scalar<double>(path, v, what.c_str());
      if (!(rl.gps_heading_fit_s >= 0.0)) fail_at(path, v, "robot_localization.gps_heading_fit_s must be ≥ 0");
    } else if (key == "until_s") {
      rl.until_s = scalar<double>(path, v, what.c_str());
      if (!(rl.until_s > 0.0))
        fail_at(path, v, "robot_localization.until_s must be a positive number of seconds");
      has_until = true;
    } else if (key == "end_s") {
      rl.end_s = scalar<double>(path, v, what.c_str());
    } else if (key == "fitness") {
      if (!v.IsSequence() || v.size() == 0)
        fail_at(path, v, "robot_localization.fitness must be a non-empty list of heldout-fixes, outage, both");
      rl.fitness.clear();
      for (const auto& f : v) {
        objectives::RlFitness fit;
        if (!objectives::parse_rl_fitness(scalar<std::string>(path, f, "a fitness"), &fit))
          fail_at(path, f, "unknown fitness, expected heldout-fixes, outage or both");
        rl.fitness.push_back(fit);
      }
    } else if (key == "space") {
      if (!objectives::parse_rl_noise_space(scalar<std::string>(path, v, what.c_str()), &rl.space))
        fail_at(path, v, "robot_localization.space must be diagonal or blocks");
    } else if (key == "input_covariances") {
      rl.input_covariances = scalar<bool>(path, v, what.c_str());
    } else if (key == "outage_s") {
      rl.outage_s.clear();
      if (v.IsSequence()) {
        for (const auto& l : v) rl.outage_s.push_back(scalar<double>(path, l, "an outage length"));
      } else {
        rl.outage_s.push_back(scalar<double>(path, v, what.c_str()));
      }
      for (double l : rl.outage_s)
        if (!(l > 0.0))
          fail_at(path, v, "robot_localization.outage_s must be > 0 (seconds, or a list of them)");
      if (rl.outage_s.empty()) fail_at(path, v, "robot_localization.outage_s must not be an empty list");
    } else if (key == "grid_levels") {
      if (!v.IsSequence()) fail_at(path, v, "robot_localization.grid_levels must be a list of decades (or [])");
      rl.search.grid_levels.clear();
      for (const auto& l : v) rl.search.grid_levels.push_back(scalar<double>(path, l, "a grid level"));
    } else if (key == "refine_decades") {
      rl.search.refine_decades = scalar<double>(path, v, what.c_str());
      if (!(rl.search.refine_decades >= 0.0)) fail_at(path, v, "robot_localization.refine_decades must be ≥ 0");
    } else if (key == "profile_step_decades") {
      rl.search.profile_step_decades = scalar<double>(path, v, what.c_str());
      if (!(rl.search.profile_step_decades > 0.0))
        fail_at(path, v, "robot_localization.profile_step_decades must be > 0");
    } else if (key == "outage_every_s") {
      rl.outage_every_s = scalar<double>(path, v, what.c_str());
      if (!(rl.outage_every_s > 0.0)) fail_at(path, v, "robot_localization.outage_every_s must be > 0");
    } else {
      fail_at(
          path, kv.first,
          fmt::format(
              "unknown robot_localization key '{}', expected params, node_name, navsat_params, tf, remap, gps_topic, "
              "gps_heading_fit_s, until_s, end_s, fitness, space, input_covariances, outage_s, "
              "outage_every_s, grid_levels, refine_decades or profile_step_decades",
              key));
    }
  }
  if (!has_params) fail_at(path, c, "robot_localization: missing 'params' (the robot's parameter file)");
  if (!has_until)
    fail_at(path, c, "robot_localization: missing 'until_s' (runs are tuned before it and scored after it)");
  if (rl.end_s && !(*rl.end_s > rl.until_s))
    fail_at(path, c["end_s"], "robot_localization.end_s must be later than until_s");
  return rl;
}

// rl-ekf tunes bags with its own fitnesses: it stands alone, and its modes
// are the stored modes of robot_localization.fitness.
void check_rl(const std::filesystem::path& path, const YAML::Node& root, Experiment* e) {
  const YAML::Node section = root["robot_localization"];
  if (!e->has_rl_models()) {
    if (section)
      fail_at(path, section, "a robot_localization section needs model rl-ekf or rl-ukf in 'models'");
    return;
  }
  if (root["leave_one_out"] && scalar<bool>(path, root["leave_one_out"], "leave_one_out"))
    fail_at(path, root["leave_one_out"],
            "leave_one_out is not supported for rl-ekf and rl-ukf (a run tunes one bag)");
  if (e->models.size() != 1)
    fail_at(path, root["models"],
            fmt::format("{} tunes bags, not tracks: list it alone in 'models' (one experiment per kind)",
                        objectives::to_string(
                            *std::find_if(e->models.begin(), e->models.end(),
                                          [](const objectives::TunedModel& m) { return m.is_rl(); }))));
  if (!section)
    fail_at(path, root,
            fmt::format("model {} needs a robot_localization section (params, until_s, ...)",
                        objectives::to_string(e->models[0])));
  if (root["modes"])
    fail_at(path, root["modes"],
            "modes do not apply to rl-ekf and rl-ukf; list robot_localization.fitness instead");
}

}  // namespace

bool Experiment::has_rl_models() const {
  return std::any_of(models.begin(), models.end(), [](const objectives::TunedModel& m) { return m.is_rl(); });
}
bool Experiment::has_ekf_models() const {
  return std::any_of(models.begin(), models.end(), [](const objectives::TunedModel& m) { return m.is_ekf(); });
}
bool Experiment::has_calibrator_models() const {
  return std::any_of(models.begin(), models.end(),
                     [](const objectives::TunedModel& m) { return m.is_calibrator(); });
}
bool Experiment::has_ukf_models() const {
  return std::any_of(models.begin(), models.end(), [](const objectives::TunedModel& m) { return m.is_ukf(); });
}

Experiment read_experiment(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw core::Failure(fmt::format("{}: cannot open the experiment file", path.string()));
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_experiment(ss.str(), path);
}

namespace {

// Every top-level key known, and the format line right.
void check_keys(const std::filesystem::path& path, const YAML::Node& root) {
  static const std::set<std::string> known = {"format",        "name",  "models",      "tracks",
                                              "modes",         "seeds", "solver",      "budget",
                                              "leave_one_out", "store", "calibration", "robot_localization"};
  for (const auto& kv : root) {
    const auto key = kv.first.as<std::string>("");
    if (!known.count(key))
      fail_at(path, kv.first,
              fmt::format("unknown key '{}', expected one of format, name, models, "
                          "tracks, modes, seeds, solver, budget, leave_one_out, store, "
                          "calibration, robot_localization",
                          key));
  }
  if (!root["format"] || root["format"].as<std::string>("") != kFormat)
    fail_at(path, root["format"] ? root["format"] : root,
            fmt::format("missing or unknown format, expected 'format: {}'", kFormat));
}

// seeds: a list, or {first, count}.
void read_seeds(const std::filesystem::path& path, const YAML::Node& root, Experiment* e) {
  const YAML::Node seeds = root["seeds"];
  if (!seeds) fail_at(path, root, "missing 'seeds'");
  if (seeds.IsMap()) {
    const auto first = scalar<std::uint64_t>(path, seeds["first"], "seeds.first");
    const auto count = scalar<int>(path, seeds["count"], "seeds.count");
    if (count < 1 || count > 100000) fail_at(path, seeds, "seeds.count must be 1..100000");
    for (int i = 0; i < count; ++i) e->seeds.push_back(first + static_cast<std::uint64_t>(i));
  } else {
    for (const auto& n : list(path, root, "seeds"))
      e->seeds.push_back(scalar<std::uint64_t>(path, n, "a seed"));
  }
}

// budget: {particles, iterations} or {evaluations}.
void read_budget(const std::filesystem::path& path, const YAML::Node& b, Experiment* e) {
  if (!b.IsMap()) fail_at(path, b, "budget must be a mapping {particles, iterations} or {evaluations}");
  for (const auto& kv : b) {
    const auto key = kv.first.as<std::string>("");
    if (key == "particles")
      e->particles = scalar<int>(path, kv.second, "budget.particles");
    else if (key == "iterations")
      e->iterations = scalar<int>(path, kv.second, "budget.iterations");
    else if (key == "evaluations")
      e->evaluations = scalar<long>(path, kv.second, "budget.evaluations");
    else
      fail_at(path, kv.first,
              fmt::format("unknown budget key '{}', expected particles, iterations or evaluations", key));
  }
}

}  // namespace

Experiment parse_experiment(const std::string& text, const std::filesystem::path& path) {
  Experiment e;
  e.file = path;
  e.text = text;
  YAML::Node root;
  try {
    root = YAML::Load(e.text);
  } catch (const YAML::ParserException& ex) {
    throw core::Failure(fmt::format("{}:{}: {}", path.string(), ex.mark.line + 1, ex.msg));
  }
  if (!root.IsMap()) fail_at(path, root, "expected a mapping (see experiments/smoke.yaml)");
  check_keys(path, root);
  const std::filesystem::path base = path.parent_path().empty() ? "." : path.parent_path();
  e.name = root["name"] ? scalar<std::string>(path, root["name"], "name") : path.stem().string();

  for (const auto& n : list(path, root, "models")) {
    objectives::TunedModel m;
    if (!objectives::parse_tuned_model(scalar<std::string>(path, n, "a model"), &m))
      fail_at(path, n, fmt::format("unknown model, expected {}", objectives::tuned_model_names()));
    e.models.push_back(m);
  }
  check_rl(path, root, &e);
  for (const auto& n : list(path, root, "tracks"))
    for (auto& t : expand(path, n, base)) e.tracks.push_back(std::move(t));
  if (e.has_rl_models()) {
    if (const YAML::Node c = root["robot_localization"]) e.robot_localization = read_rl(path, c, base);
  } else {
    for (const auto& n : list(path, root, "modes")) {
      const auto mode_text = scalar<std::string>(path, n, "a mode");
      objectives::FitnessMode m{};
      if (!objectives::parse_fitness_mode(mode_text, &m))
        fail_at(path, n,
                fmt::format("mode {} is out of range, expected {}", mode_text,
                            objectives::fitness_mode_choices()));
      e.modes.push_back(m);
    }
  }
  read_seeds(path, root, &e);
  if (const YAML::Node n = root["solver"]) {
    std::string why;
    const std::optional<tuner::SolverChoice> solver = tuner::SolverChoice::parse(
        scalar<std::string>(path, n, "solver"), &why);
    if (!solver) fail_at(path, n, why);
    e.solver = *solver;
  }
  if (const YAML::Node b = root["budget"]) read_budget(path, b, &e);
  if (root["leave_one_out"]) e.leave_one_out = scalar<bool>(path, root["leave_one_out"], "leave_one_out");
  if (e.leave_one_out && e.tracks.size() < 2)
    fail_at(path, root["leave_one_out"], "leave_one_out needs at least two tracks");
  if (const YAML::Node c = root["calibration"]) read_calibration(path, c, &e.calibration);
  e.store = root["store"] ? base / scalar<std::string>(path, root["store"], "store")
                          : base / (e.name + ".sqlite");
  return e;
}

}  // namespace odotune::formats
