// `odotune import <dataset> ...`: converts a third-party recording to an
// odotune track file (jobs/import_job.h over tracks/importers.h); this file
// only reads flags and prints the one-line summary.
#include <memory>
#include <string>

#include <fmt/format.h>

#include "cli/commands.h"
#include "jobs/import_job.h"

namespace odotune::cli {

namespace {

struct Dataset {
  ImportDataset id;
  const char *name, *description, *example, *input_name, *input_help;
};

const Dataset kDatasets[] = {
    {ImportDataset::mrclam, "mrclam",
     "UTIAS MRCLAM (Leung et al., IJRR 2011): one robot's commanded v, w (RobotN_Odometry.dat) "
     "and Vicon pose (RobotN_Groundtruth.dat), merged on their common Unix clock",
     "odotune import mrclam ../shared/data/real/mrclam7 --robot 1 -o mrclam7-robot1.csv", "DIR",
     "MRCLAM dataset folder holding RobotN_Odometry.dat and RobotN_Groundtruth.dat"},
    {ImportDataset::optiodom, "optiodom",
     "OptiOdom (Sousa et al., JIRS 2022): one synchronised run <id>_run-NN.csv (encoder "
     "ticks, OptiTrack ground truth); robot geometry from <id>_metadata.csv beside it, "
     "velocity commands from the robot log <id>.csv when they align with the run",
     "odotune import optiodom "
     "../shared/data/real/optiodom_diff/circular/231220200146/231220200146_run-01.csv -o circular-run01.csv",
     "RUN.csv", "synchronised run file <id>_run-NN.csv"},
    {ImportDataset::litw, "litw",
     "UTIAS Lost in the Woods (AER1513 dataset2.mat) from its CSV export litw_series.csv: "
     "odometry v, w and ground truth where valid; the noise variances of litw_scalars.csv "
     "beside it become metadata",
     "odotune import litw ../shared/data/real/utias_lost_in_the_woods/derived/litw_series.csv -o litw.csv",
     "SERIES.csv", "the derived file litw_series.csv"},
};

}  // namespace

void register_import(CLI::App& app) {
  auto* imp = app.add_subcommand("import", "Convert a recorded third-party dataset into an odotune track file");
  imp->require_subcommand(1);
  imp->footer("Datasets: mrclam (UTIAS MRCLAM), optiodom (OptiOdom diff-drive runs), litw (UTIAS "
              "Lost in the Woods). Every track cites its source, citation and licence in its metadata.\n"
              "Example:\n  odotune import optiodom ../shared/data/real/optiodom_diff/square/231220200045/"
              "231220200045_run-01.csv -o square-run01.csv");
  for (const Dataset& d : kDatasets) {
    auto req = std::make_shared<ImportRequest>();
    req->dataset = d.id;
    auto* sub = imp->add_subcommand(d.name, d.description);
    sub->add_option(d.input_name, req->input, d.input_help)->required();
    sub->add_option("-o,--output", req->output, "track file to write (odotune-track/1 CSV)")
        ->required()
        ->option_text("TRACK.csv REQUIRED");
    sub->footer(std::string("Example:\n  ") + d.example);
    if (d.id == ImportDataset::mrclam)
      sub->add_option("--robot", req->robot, "robot number N (1 to 5)")->required();
    sub->callback([req] {
      const ImportOutcome o = run_import(*req);
      fmt::print("{}: {} rows, {:.3f} s, columns {}{}\n", req->output, o.rows, o.duration_s, o.columns,
                 o.no_commands_why ? "; velocity commands " + *o.no_commands_why : "");
    });
  }
}

}  // namespace odotune::cli
