// `odotune import <dataset>`: a third-party recording converted to a track
// file by one importer of odotune/tracks/importers.h, and the numbers of the summary
// line. The command reads the flags and prints.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <odotune/tracks/import_rosbag.h>
#include <odotune/tracks/track.h>

namespace odotune::jobs {

enum class ImportDataset { mrclam, optiodom, litw, rosbag };

struct ImportRequest {
  ImportDataset dataset = ImportDataset::optiodom;
  std::string
      input;      // dataset folder (mrclam) or file (optiodom: the run, litw: litw_series.csv; rosbag: the bag)
  int robot = 0;  // mrclam only: robot N, 1..5
  std::string output;                  // track file to write
  tracks::RosbagImportOptions rosbag;  // rosbag only
};

struct ImportOutcome {
  std::size_t rows = 0;
  double duration_s = 0.0;
  std::string columns;  // column_list()
  // Why the track has no velocity commands (its source.cmd_alignment); none
  // when it has them or the importer says nothing.
  std::optional<std::string> no_commands_why;
  // rosbag: what each column came from (the track's source.* lines), to print.
  std::vector<std::string> notes;
};

// Throws on an unreadable recording (TrackError naming the file), an empty
// output (core::Failure) or a track that cannot be written.
ImportOutcome run_import(const ImportRequest& request);

// "t,ticks_l,ticks_r,v_cmd,..." in the order the track writer uses.
std::string column_list(const tracks::Track& track);

}  // namespace odotune::jobs
