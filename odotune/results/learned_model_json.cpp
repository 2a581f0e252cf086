#include <odotune/results/learned_model_json.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include <odotune/core/atomic_file.h>
#include <odotune/results/lstm_json.h>

namespace odotune::results {

namespace {

using json = nlohmann::json;
constexpr double kModelNaN = std::numeric_limits<double>::quiet_NaN();

json num_model(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// Field access with one-line errors "FILE: PATH: what; expected …".
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw std::invalid_argument(fmt::format("{}: {}: {}", file_, path, what));
  }

  const json& field(const json& obj, const std::string& path, const char* key) const {
    if (!obj.is_object()) fail(path, "not an object; expected {…}");
    const auto it = obj.find(key);
    if (it == obj.end()) fail(join(path, key), "missing");
    return *it;
  }
  bool has(const json& obj, const char* key) const { return obj.is_object() && obj.contains(key); }

  double number(const json& obj, const std::string& path, const char* key, bool positive, bool nullable) const {
    const json& v = field(obj, path, key);
    if (nullable && v.is_null()) return kModelNaN;
    if (!v.is_number())
      fail(join(path, key), fmt::format("{} is not a number; expected {}", short_dump(v),
                                        nullable ? "a number or null" : "a number"));
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail(join(path, key), "not finite; expected a finite number");
    if (positive && !(d > 0.0)) fail(join(path, key), fmt::format("{} must be > 0", d));
    if (!positive && d < 0.0) fail(join(path, key), fmt::format("{} must be >= 0", d));
    return d;
  }
  std::uint64_t count(const json& obj, const std::string& path, const char* key) const {
    const json& v = field(obj, path, key);
    if (!v.is_number_integer() ||
        (v.is_number_integer() && !v.is_number_unsigned() && v.get<std::int64_t>() < 0))
      fail(join(path, key), fmt::format("{} is not a whole number >= 0", short_dump(v)));
    return v.get<std::uint64_t>();
  }
  std::string text(const json& obj, const std::string& path, const char* key) const {
    const json& v = field(obj, path, key);
    if (!v.is_string()) fail(join(path, key), fmt::format("{} is not a string", short_dump(v)));
    return v.get<std::string>();
  }
  std::vector<std::string> texts(const json& obj, const std::string& path, const char* key) const {
    const json& v = field(obj, path, key);
    if (!v.is_array()) fail(join(path, key), "not an array; expected a list of names");
    std::vector<std::string> out;
    for (std::size_t i = 0; i < v.size(); ++i) {
      if (!v[i].is_string()) fail(fmt::format("{}[{}]", join(path, key), i), "not a string");
      out.push_back(v[i].get<std::string>());
    }
    return out;
  }
  const std::string& file() const { return file_; }

  static std::string join(const std::string& path, const char* key) {
    return path.empty() ? key : path + "." + key;
  }

 private:
  static std::string short_dump(const json& v) {
    std::string s = v.dump();
    return s.size() > 40 ? s.substr(0, 37) + "..." : s;
  }
  std::string file_;
};

json training_json(const ModelTrainingRecord& t) {
  const auto net = [](const NetTrainingRecord& n) {
    return json{{"iterations", n.iterations},
                {"train_mae", num_model(n.train_mae)},
                {"validation_mae", num_model(n.validation_mae)}};
  };
  return {{"train_windows", t.train_windows},
          {"validation_windows", t.validation_windows},
          {"seconds", t.seconds},
          {"v", net(t.v)},
          {"w", net(t.w)}};
}

ModelTrainingRecord parse_training(const Reader& r, const json& j, const std::string& path) {
  ModelTrainingRecord t;
  t.train_windows = static_cast<std::size_t>(r.count(j, path, "train_windows"));
  t.validation_windows = static_cast<std::size_t>(r.count(j, path, "validation_windows"));
  t.seconds = r.number(j, path, "seconds", false, false);
  for (const char* which : {"v", "w"}) {
    const std::string p = Reader::join(path, which);
    const json& n = r.field(j, path, which);
    NetTrainingRecord& out = which[0] == 'v' ? t.v : t.w;
    const std::uint64_t it = r.count(n, p, "iterations");
    if (it > 1000000000ULL) r.fail(Reader::join(p, "iterations"), "implausibly large; expected < 1e9");
    out.iterations = static_cast<int>(it);
    out.train_mae = r.number(n, p, "train_mae", false, true);
    out.validation_mae = r.number(n, p, "validation_mae", false, true);
  }
  return t;
}

template <class Net>
Net parse_net(const Reader& r, const json& obj, const std::string& path, const char* key) {
  const json& j = r.field(obj, path, key);
  try {
    return lstm_from_json<Net::kInputs, Net::kHidden>(j);
  } catch (const std::exception& e) {
    r.fail(Reader::join(path, key), e.what());
  }
}

learned::OdometryNet parse_odometry_net(const Reader& r, const json& obj, const std::string& path,
                                        const char* key) {
  const json& j = r.field(obj, path, key);
  try {
    return odometry_net_from_json(j);
  } catch (const std::exception& e) {
    r.fail(Reader::join(path, key), e.what());
  }
}

}  // namespace

ModelTrainingRecord training_record(const learned::LstmTrainingSummary& v,
                                    const learned::LstmTrainingSummary& w, std::size_t train_windows,
                                    std::size_t validation_windows, double seconds) {
  ModelTrainingRecord t;
  t.v = {v.iterations, v.train_mae, v.validation_mae};
  t.w = {w.iterations, w.train_mae, w.validation_mae};
  t.train_windows = train_windows;
  t.validation_windows = validation_windows;
  t.seconds = seconds;
  return t;
}

json learned_model_json(const LearnedModelFile& m) {
  json j;
  j["format"] = kLearnedModelFormat;
  const learned::LearnedOdometryModel& o = m.odometry;
  j["odometry"] = {{"rate_hz", o.rate_hz},
                   {"ticks_per_rev", o.ticks_per_rev},
                   {"target", std::string(learned::to_string(o.target))},
                   {"input", std::string(tracks::to_string(o.input))},
                   {"features", std::string(learned::to_string(o.features))},
                   {"gyro", o.gyro},
                   {"v_beats_kinematic", o.v_beats_kinematic},
                   {"w_beats_kinematic", o.w_beats_kinematic},
                   {"v_validation_mae", o.v_validation_mae},
                   {"w_validation_mae", o.w_validation_mae},
                   {"v_kinematic_mae", o.v_kinematic_mae},
                   {"w_kinematic_mae", o.w_kinematic_mae},
                   {"v_net", odometry_net_to_json(o.v_net)},
                   {"w_net", odometry_net_to_json(o.w_net)}};
  if (m.detector)
    j["detector"] = {{"floor_var_v", m.detector->floor_var_v},
                     {"floor_var_w", m.detector->floor_var_w},
                     {"previous_lag", m.detector->previous_lag},
                     {"max_log_ratio_v", m.detector->max_log_ratio_v},
                     {"max_log_ratio_w", m.detector->max_log_ratio_w},
                     {"v_net", lstm_to_json(m.detector->v_net)},
                     {"w_net", lstm_to_json(m.detector->w_net)},
                     {"drive", std::string(learned::to_string(m.detector->drive))},
                     {"input", std::string(tracks::to_string(m.detector->input))},
                     {"flag_var_v", m.detector->flag_var_v},
                     {"flag_var_w", m.detector->flag_var_w}};
  const LearnedModelProvenance& p = m.provenance;
  json prov = {{"tracks", p.tracks},
               {"slip_tracks", p.slip_tracks},
               {"seed", p.seed},
               {"odometry", training_json(p.odometry)},
               {"retrains", p.retrains},
               {"retrain_tracks", p.retrain_tracks},
               {"created_by", p.created_by}};
  if (p.detector) prov["detector"] = training_json(*p.detector);
  if (p.selection) prov["selection"] = *p.selection;
  j["provenance"] = prov;
  return j;
}

LearnedModelFile parse_learned_model(const json& j, const std::string& file) {
  const Reader r(file);
  if (!j.is_object()) r.fail("(top level)", "not a JSON object; expected an odotune-learned/1 model file");
  const std::string format = r.text(j, "", "format");
  if (format != kLearnedModelFormat)
    r.fail("format", fmt::format("'{}'; expected '{}'", format, kLearnedModelFormat));

  LearnedModelFile m;
  const json& o = r.field(j, "", "odometry");
  m.odometry.rate_hz = r.number(o, "odometry", "rate_hz", true, false);
  // Files written before the keys existed hold the paper's velocity nets on wheels.
  if (r.has(o, "input")) {
    const std::string input = r.text(o, "odometry", "input");
    if (!tracks::parse_odometry_input(input, &m.odometry.input))
      r.fail("odometry.input", fmt::format("'{}'; expected 'wheels', 'twist' or 'commands'", input));
  }
  const bool wheels = m.odometry.input == tracks::OdometryInput::wheels;
  m.odometry.ticks_per_rev = r.number(o, "odometry", "ticks_per_rev", wheels, false);
  if (r.has(o, "target")) {
    const std::string target = r.text(o, "odometry", "target");
    if (!learned::parse_learned_target(target, &m.odometry.target))
      r.fail("odometry.target", fmt::format("'{}'; expected 'velocity' or 'correction'", target));
  }
  if (r.has(o, "features")) {
    const std::string features = r.text(o, "odometry", "features");
    if (!learned::parse_learned_features(features, &m.odometry.features))
      r.fail("odometry.features", fmt::format("'{}'; expected 'paper', 'channel' or 'both'", features));
  } else if (m.odometry.target == learned::LearnedTarget::correction) {
    r.fail("odometry.features", "missing: a correction model written before the features were recorded; "
                                "train it again (odotune learn train)");
  }
  if (r.has(o, "gyro")) {
    if (!o["gyro"].is_boolean()) r.fail("odometry.gyro", "not true or false; expected a boolean");
    m.odometry.gyro = o["gyro"].get<bool>();
  }
  for (auto [key, flag] : {std::pair{"v_beats_kinematic", &m.odometry.v_beats_kinematic},
                           std::pair{"w_beats_kinematic", &m.odometry.w_beats_kinematic}})
    if (r.has(o, key)) {
      if (!o[key].is_boolean()) r.fail(std::string("odometry.") + key, "not true or false; expected a boolean");
      *flag = o[key].get<bool>();
    }
  m.odometry.v_validation_mae = r.number(o, "odometry", "v_validation_mae", false, false);
  m.odometry.w_validation_mae = r.number(o, "odometry", "w_validation_mae", false, false);
  if (r.has(o, "v_kinematic_mae"))
    m.odometry.v_kinematic_mae = r.number(o, "odometry", "v_kinematic_mae", false, false);
  if (r.has(o, "w_kinematic_mae"))
    m.odometry.w_kinematic_mae = r.number(o, "odometry", "w_kinematic_mae", false, false);
  m.odometry.v_net = parse_odometry_net(r, o, "odometry", "v_net");
  m.odometry.w_net = parse_odometry_net(r, o, "odometry", "w_net");
  if (m.odometry.v_net.activation() != learned::OutputActivation::linear ||
      m.odometry.w_net.activation() != learned::OutputActivation::linear)
    r.fail("odometry.v_net/w_net", "a ReLU output; expected the velocity nets' linear output (paper §4)");
  std::string why;
  if (!m.odometry.IsValid(&why)) r.fail("odometry", why);

  if (r.has(j, "detector") && !j["detector"].is_null()) {
    const json& d = j["detector"];
    learned::SlipDetectorModel det;
    det.floor_var_v = r.number(d, "detector", "floor_var_v", true, false);
    det.floor_var_w = r.number(d, "detector", "floor_var_w", true, false);
    det.max_log_ratio_v = r.number(d, "detector", "max_log_ratio_v", true, false);
    det.max_log_ratio_w = r.number(d, "detector", "max_log_ratio_w", true, false);
    // Files written before these keys: the paper's detector (power, wheels), no flag.
    if (r.has(d, "drive")) {
      const std::string drive = r.text(d, "detector", "drive");
      if (!learned::parse_slip_drive(drive, &det.drive))
        r.fail("detector.drive", fmt::format("'{}'; expected 'power', 'commands' or 'none'", drive));
    }
    if (r.has(d, "input")) {
      const std::string input = r.text(d, "detector", "input");
      if (!tracks::parse_odometry_input(input, &det.input))
        r.fail("detector.input", fmt::format("'{}'; expected 'wheels', 'twist' or 'commands'", input));
    }
    if (r.has(d, "flag_var_v")) det.flag_var_v = r.number(d, "detector", "flag_var_v", false, false);
    if (r.has(d, "flag_var_w")) det.flag_var_w = r.number(d, "detector", "flag_var_w", false, false);
    det.v_net = parse_net<learned::SlipNet>(r, d, "detector", "v_net");
    det.w_net = parse_net<learned::SlipNet>(r, d, "detector", "w_net");
    const std::uint64_t lag = r.count(d, "detector", "previous_lag");
    if (lag < 1 || lag > static_cast<std::uint64_t>(det.v_net.window))
      r.fail("detector.previous_lag", fmt::format("{}; expected 1..{} (the window)", lag, det.v_net.window));
    det.previous_lag = static_cast<int>(lag);
    m.detector = det;
  }

  const json& p = r.field(j, "", "provenance");
  LearnedModelProvenance& prov = m.provenance;
  prov.tracks = r.texts(p, "provenance", "tracks");
  prov.slip_tracks = r.texts(p, "provenance", "slip_tracks");
  prov.seed = r.count(p, "provenance", "seed");
  prov.odometry = parse_training(r, r.field(p, "provenance", "odometry"), "provenance.odometry");
  if (r.has(p, "detector") && !p["detector"].is_null())
    prov.detector = parse_training(r, p["detector"], "provenance.detector");
  const std::uint64_t retrains = r.count(p, "provenance", "retrains");
  if (retrains > 1000000000ULL) r.fail("provenance.retrains", "implausibly large; expected < 1e9");
  prov.retrains = static_cast<int>(retrains);
  prov.retrain_tracks = r.texts(p, "provenance", "retrain_tracks");
  prov.created_by = r.text(p, "provenance", "created_by");
  if (r.has(p, "selection") && !p["selection"].is_null()) {
    if (!p["selection"].is_object()) r.fail("provenance.selection", "not an object; expected {…}");
    prov.selection = p["selection"];
  }
  return m;
}

void write_learned_model(const std::filesystem::path& path, const LearnedModelFile& model) {
  core::write_atomically(path, "learned model", learned_model_json(model).dump(2) + "\n");
}

LearnedModelFile read_learned_model(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw std::invalid_argument(fmt::format("{}: no such model file; expected an {} file (odotune learn train "
                                            "--model-out)",
                                            path.string(), kLearnedModelFormat));
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::invalid_argument(fmt::format("{}: cannot open the model file for reading", path.string()));
  std::stringstream ss;
  ss << in.rdbuf();
  json j;
  try {
    j = json::parse(ss.str());
  } catch (const json::parse_error& e) {
    throw std::invalid_argument(fmt::format("{}: not valid JSON (byte {}); expected an {} file", path.string(),
                                            e.byte, kLearnedModelFormat));
  }
  return parse_learned_model(j, path.string());
}

}  // namespace odotune::results
