#include <odotune/jobs/import_job.h>

#include <stdexcept>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include <odotune/core/failure.h>
#include <odotune/tracks/importers.h>
#include <odotune/tracks/track_io.h>

namespace odotune::jobs {

namespace {
tracks::Track import_track(const ImportRequest& r) {
  switch (r.dataset) {
    case ImportDataset::mrclam: return tracks::import_mrclam(r.input, r.robot);
    case ImportDataset::optiodom: return tracks::import_optiodom(r.input);
    case ImportDataset::litw: return tracks::import_litw(r.input);
    case ImportDataset::rosbag: return tracks::import_rosbag(r.input, r.rosbag);
  }
  throw std::logic_error("run_import: unknown dataset");
}
}  // namespace

std::string column_list(const tracks::Track& track) {
  std::vector<std::string_view> names = {"t"};
  if (!track.ticks_l().empty()) names.emplace_back("ticks_l");
  if (!track.ticks_r().empty()) names.emplace_back("ticks_r");
  for (int c = 0; c < tracks::kNumCols; ++c)
    if (track.has(static_cast<tracks::Col>(c)))
      names.push_back(tracks::column_name(static_cast<tracks::Col>(c)));
  return fmt::format("{}", fmt::join(names, ","));
}

ImportOutcome run_import(const ImportRequest& r) {
  const tracks::Track track = import_track(r);
  if (r.output.empty()) throw core::Failure("no output file given (-o TRACK.csv)");
  tracks::write_track(track, r.output);
  ImportOutcome out{track.size(), track.duration_s(), column_list(track), std::nullopt, {}};
  if (!track.has_cmd()) out.no_commands_why = track.meta().get("source.cmd_alignment");
  if (r.dataset == ImportDataset::rosbag)
    for (const char* key :
         {"source.odometry", "source.gyro", "source.fixes", "source.ground_truth", "source.stamps"})
      if (const auto v = track.meta().get(key)) out.notes.push_back(std::string(key).substr(7) + ": " + *v);
  return out;
}

}  // namespace odotune::jobs
