#include <odotune/jobs/demo_job.h>

#include <filesystem>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <odotune/core/failure.h>
#include <odotune/formats/config_yaml.h>
#include <odotune/jobs/tune_json.h>
#include <odotune/tracks/track_io.h>

namespace odotune::jobs {

DemoOutcome run_demo(const DemoRequest& request, const DemoCallbacks& cb) {
  std::vector<std::string> paths;
  for (int i = 1; i <= 5; ++i) {
    const auto p = std::filesystem::path(request.data_dir) / fmt::format("track{}.csv", i);
    if (!std::filesystem::exists(p))
      throw core::Failure(fmt::format("{}: reference track not found (use --data DIR)", p.string()));
    paths.push_back(p.string());
  }
  const std::vector<tracks::Track> tracks = tracks::load_tracks(paths);
  std::vector<PreparedTrack> prepared;
  for (const auto& t : tracks) prepared.push_back(prepare_track(t));

  const filters::NoiseModel models[] = {filters::NoiseModel::rq, filters::NoiseModel::alpha,
                                        filters::NoiseModel::gyro};
  const std::atomic<bool>* stop = cb.started ? cb.started() : nullptr;
  DemoOutcome out;
  out.evaluations_per_tune = static_cast<long>(request.particles) * (request.iterations + 1);
  nlohmann::json all = nlohmann::json::array();
  const long total = static_cast<long>(prepared.size()) * 3;
  long done = 0;
  for (const auto& p : prepared) {
    for (auto model : models) {
      if (cb.tune_started)
        cb.tune_started(fmt::format("demo {} {}", p.name, filters::to_string(model)), done, total);
      TuneRequest req;
      req.model = model;
      req.mode = request.mode;
      req.seed = request.seed;
      req.particles = request.particles;
      req.iterations = request.iterations;
      req.stop = stop;
      TuneOutcome o = run_tune({&p}, req);
      if (stop && stop->load()) throw core::Failure("interrupted", 130);
      out.seconds += o.summary.seconds;
      all.push_back(tune_json(o));
      out.rows.push_back({p.name, model, std::move(o)});
      ++done;
      if (cb.row) cb.row(out.rows.back(), done, total);
    }
  }
  if (cb.finished) cb.finished(out);
  if (!request.json_out.empty()) formats::write_file_atomically(request.json_out, all.dump(2) + "\n");
  return out;
}

}  // namespace odotune::jobs
