// `odotune import <dataset> ...`: converts a third-party recording to an
// odotune track file (the importers live in tracks/importers.h; this file only
// reads flags, calls one importer, writes the track and prints a summary).
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/commands.h"
#include "core/failure.h"
#include "tracks/importers.h"
#include "tracks/track_io.h"

namespace odotune::cli {

namespace {

struct ImportArgs {
  std::string input;  // folder (mrclam) or file
  int robot = 0;      // mrclam only
  std::string output;
};

// "t,ticks_l,ticks_r,v_cmd,..." in the order the writer uses.
std::string column_list(const Track& track) {
  std::vector<std::string_view> names = {"t"};
  if (!track.ticks_l().empty()) names.push_back("ticks_l");
  if (!track.ticks_r().empty()) names.push_back("ticks_r");
  for (int c = 0; c < kNumCols; ++c)
    if (track.has(static_cast<Col>(c))) names.push_back(column_name(static_cast<Col>(c)));
  return fmt::format("{}", fmt::join(names, ","));
}

// Writes the track and prints the one-line summary on stdout.
void finish(const Track& track, const std::string& output) {
  if (output.empty()) throw Failure("no output file given (-o TRACK.csv)");
  write_track(track, output);
  std::string note;
  if (!track.has_cmd())
    if (const auto why = track.meta().get("source.cmd_alignment")) note = "; velocity commands " + *why;
  fmt::print("{}: {} rows, {:.3f} s, columns {}{}\n", output, track.size(), track.duration_s(),
             column_list(track), note);
}

CLI::App* add_dataset(CLI::App* parent, const std::string& name, const std::string& description,
                      const std::string& footer, const std::shared_ptr<ImportArgs>& args,
                      const std::string& input_name, const std::string& input_help) {
  auto* sub = parent->add_subcommand(name, description);
  sub->add_option(input_name, args->input, input_help)->required();
  sub->add_option("-o,--output", args->output, "track file to write (odotune-track/1 CSV)")
      ->required()
      ->option_text("TRACK.csv REQUIRED");
  sub->footer(footer);
  return sub;
}

}  // namespace

void register_import(CLI::App& app) {
  auto* imp = app.add_subcommand(
      "import", "Convert a recorded third-party dataset into an odotune track file");
  imp->require_subcommand(1);
  imp->footer(
      "Datasets: mrclam (UTIAS MRCLAM), optiodom (OptiOdom diff-drive runs), litw (UTIAS "
      "Lost in the Woods). Every track cites its source, citation and licence in its metadata.\n"
      "Example:\n  odotune import optiodom ../shared/data/real/optiodom_diff/square/231220200045/"
      "231220200045_run-01.csv -o square-run01.csv");

  {
    auto args = std::make_shared<ImportArgs>();
    auto* sub = add_dataset(
        imp, "mrclam",
        "UTIAS MRCLAM (Leung et al., IJRR 2011): one robot's commanded v, w (RobotN_Odometry.dat) "
        "and Vicon pose (RobotN_Groundtruth.dat), merged on their common Unix clock",
        "Example:\n  odotune import mrclam ../shared/data/real/mrclam7 --robot 1 -o mrclam7-robot1.csv",
        args, "DIR", "MRCLAM dataset folder holding RobotN_Odometry.dat and RobotN_Groundtruth.dat");
    sub->add_option("--robot", args->robot, "robot number N (1 to 5)")->required();
    sub->callback([args] { finish(import_mrclam(args->input, args->robot), args->output); });
  }
  {
    auto args = std::make_shared<ImportArgs>();
    auto* sub = add_dataset(
        imp, "optiodom",
        "OptiOdom (Sousa et al., JIRS 2022): one synchronised run <id>_run-NN.csv (encoder "
        "ticks, OptiTrack ground truth); robot geometry from <id>_metadata.csv beside it, "
        "velocity commands from the robot log <id>.csv when they align with the run",
        "Example:\n  odotune import optiodom "
        "../shared/data/real/optiodom_diff/circular/231220200146/231220200146_run-01.csv -o circular-run01.csv",
        args, "RUN.csv", "synchronised run file <id>_run-NN.csv");
    sub->callback([args] { finish(import_optiodom(args->input), args->output); });
  }
  {
    auto args = std::make_shared<ImportArgs>();
    auto* sub = add_dataset(
        imp, "litw",
        "UTIAS Lost in the Woods (AER1513 dataset2.mat) from its CSV export litw_series.csv: "
        "odometry v, w and ground truth where valid; the noise variances of litw_scalars.csv "
        "beside it become metadata",
        "Example:\n  odotune import litw ../shared/data/real/utias_lost_in_the_woods/derived/litw_series.csv "
        "-o litw.csv",
        args, "SERIES.csv", "the derived file litw_series.csv");
    sub->callback([args] { finish(import_litw(args->input), args->output); });
  }
}

}  // namespace odotune::cli
