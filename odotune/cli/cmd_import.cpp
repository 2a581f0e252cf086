// `odotune import <dataset> ...`: converts a third-party recording to an
// odotune track file (odotune/jobs/import_job.h over odotune/tracks/importers.h); this file
// only reads flags and prints the one-line summary.
#include <array>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include <odotune/bags/bag.h>
#include <odotune/cli/choices.h>
#include <odotune/cli/commands.h>
#include <odotune/core/failure.h>
#include <odotune/jobs/import_job.h>
#include <odotune/tracks/import_rosbag.h>

namespace odotune::cli {

namespace {

// --stamps: which time a bag's message is placed at.
enum class BagStamps { header, receive };
constexpr std::array<BagStamps, 2> kAllBagStamps = {BagStamps::header, BagStamps::receive};
std::string_view to_string(BagStamps s) { return s == BagStamps::receive ? "receive" : "header"; }

struct Dataset {
  jobs::ImportDataset id;
  const char *name, *description, *example, *input_name, *input_help;
};

const Dataset kDatasets[] = {
    {jobs::ImportDataset::mrclam, "mrclam",
     "UTIAS MRCLAM (Leung et al., IJRR 2011): one robot's commanded v, w (RobotN_Odometry.dat) "
     "and Vicon pose (RobotN_Groundtruth.dat), merged on their common Unix clock",
     "odotune import mrclam ../shared/data/real/mrclam7 --robot 1 -o mrclam7-robot1.csv", "DIR",
     "MRCLAM dataset folder holding RobotN_Odometry.dat and RobotN_Groundtruth.dat"},
    {jobs::ImportDataset::optiodom, "optiodom",
     "OptiOdom (Sousa et al., JIRS 2022): one synchronised run <id>_run-NN.csv (encoder "
     "ticks, OptiTrack ground truth); robot geometry from <id>_metadata.csv beside it, "
     "velocity commands from the robot log <id>.csv when they align with the run",
     "odotune import optiodom "
     "../shared/data/real/optiodom_diff/circular/231220200146/231220200146_run-01.csv -o circular-run01.csv",
     "RUN.csv", "synchronised run file <id>_run-NN.csv"},
    {jobs::ImportDataset::litw, "litw",
     "UTIAS Lost in the Woods (AER1513 dataset2.mat) from its CSV export litw_series.csv: "
     "odometry v, w and ground truth where valid; the noise variances of litw_scalars.csv "
     "beside it become metadata",
     "odotune import litw ../shared/data/real/utias_lost_in_the_woods/derived/litw_series.csv -o litw.csv",
     "SERIES.csv", "the derived file litw_series.csv"},
};

}  // namespace

namespace {

void register_import_rosbag(CLI::App& imp) {
  auto req = std::make_shared<jobs::ImportRequest>();
  req->dataset = jobs::ImportDataset::rosbag;
  auto list = std::make_shared<bool>(false);
  auto rpy = std::make_shared<std::vector<double>>();
  auto radius = std::make_shared<double>(0.0);
  auto base = std::make_shared<double>(0.0);
  auto* sub = imp.add_subcommand(
      "rosbag",
      std::string("A ROS bag: ROS 1 .bag (") +
          (bags::ros1_supported() ? "supported"
                                  : "NOT supported by this build: built without librosbag_storage") +
          "), MCAP (.mcap), rosbag2 SQLite (.db3) or a rosbag2 folder: odometry (nav_msgs/Odometry twist, "
          "or sensor_msgs/JointState wheels), gyro (sensor_msgs/Imu), position fixes (sensor_msgs/NavSatFix "
          "to local east/north, or a pose topic) and, when named, ground truth");
  sub->add_option("BAG", req->input, "bag file or rosbag2 folder")->required();
  sub->add_option("-o,--output", req->output, "track file to write (odotune-track/1 CSV)")
      ->option_text("TRACK.csv");
  sub->add_flag("--list", *list, "list the bag's topics, types and counts, and write nothing");
  sub->add_option("--odom-topic", req->rosbag.odom_topic,
                  "nav_msgs/Odometry (twist → v_cmd, w_cmd) or sensor_msgs/JointState topic (default: the one "
                  "Odometry topic that is not a filter's output)");
  sub->add_option("--imu-topic", req->rosbag.imu_topic,
                  "sensor_msgs/Imu topic, or none (default: the one Imu topic)");
  sub->add_option(
      "--fix-topic", req->rosbag.fix_topic,
      "sensor_msgs/NavSatFix, PoseWithCovarianceStamped or PoseStamped topic, or none (default: the one "
      "NavSatFix topic)");
  sub->add_option("--gt-topic", req->rosbag.gt_topic,
                  "ground-truth topic (Odometry, PoseStamped or PoseWithCovarianceStamped; default: none)");
  sub->add_option("--imu-rpy", *rpy,
                  "R,P,Y: the IMU's mounting roll, pitch, yaw relative to the base frame [rad] (default: from "
                  "/tf_static when the bag has it, else none)")
      ->delimiter(',')
      ->expected(3);
  add_choice_option(
      sub, "--stamps", [req](BagStamps s) { req->rosbag.receive_time_stamps = s == BagStamps::receive; },
      kAllBagStamps, "header: the messages' header stamps (default); receive: the times the bag recorded them");
  sub->add_option("--left-joint", req->rosbag.left_joint, "JointState odometry: the left wheel's joint name");
  sub->add_option("--right-joint", req->rosbag.right_joint,
                  "JointState odometry: the right wheel's joint name");
  sub->add_option("--wheel-radius", *radius,
                  "wheel radius [m] (JointState odometry; written as robot metadata)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--wheel-base", *base, "wheel base [m] (JointState odometry; written as robot metadata)")
      ->check(CLI::PositiveNumber);
  sub->footer("Examples:\n"
              "  odotune import rosbag ../shared/data/real/robot_localization_bags/test1.bag --list\n"
              "  odotune import rosbag ../shared/data/real/robot_localization_bags/ros2/test1.mcap \\\n"
              "      --imu-rpy -1.5707963,0,1.5707963 -o husky.csv\n"
              "Every conversion (topics, frames, the fixes' local origin, stamps) is written into the track's "
              "source.* metadata and printed.");
  sub->callback([req, list, rpy, radius, base] {
    if (*list) {
      fmt::print("{}:\n", req->input);
      for (const std::string& line : tracks::describe_bag_topics(req->input)) fmt::print("{}\n", line);
      return;
    }
    if (req->output.empty())
      throw core::Failure("import rosbag: no output file given (-o TRACK.csv, or --list)");
    if (!rpy->empty()) req->rosbag.imu_rpy_rad = std::array<double, 3>{(*rpy)[0], (*rpy)[1], (*rpy)[2]};
    if (*radius > 0.0) req->rosbag.wheel_radius_m = *radius;
    if (*base > 0.0) req->rosbag.wheel_base_m = *base;
    const jobs::ImportOutcome o = jobs::run_import(*req);
    fmt::print("{}: {} rows, {:.3f} s, columns {}\n", req->output, o.rows, o.duration_s, o.columns);
    for (const std::string& n : o.notes) fmt::print("  {}\n", n);
  });
}

}  // namespace

void register_import(CLI::App& app) {
  auto* imp = app.add_subcommand("import", "Convert a recorded third-party dataset into an odotune track file");
  imp->require_subcommand(1);
  imp->footer("Datasets: mrclam (UTIAS MRCLAM), optiodom (OptiOdom diff-drive runs), litw (UTIAS "
              "Lost in the Woods); rosbag (a robot's own ROS 1 / ROS 2 bag). Every track cites its source, "
              "citation and licence in its metadata.\n"
              "Example:\n  odotune import optiodom ../shared/data/real/optiodom_diff/square/231220200045/"
              "231220200045_run-01.csv -o square-run01.csv");
  for (const Dataset& d : kDatasets) {
    auto req = std::make_shared<jobs::ImportRequest>();
    req->dataset = d.id;
    auto* sub = imp->add_subcommand(d.name, d.description);
    sub->add_option(d.input_name, req->input, d.input_help)->required();
    sub->add_option("-o,--output", req->output, "track file to write (odotune-track/1 CSV)")
        ->required()
        ->option_text("TRACK.csv REQUIRED");
    sub->footer(std::string("Example:\n  ") + d.example);
    if (d.id == jobs::ImportDataset::mrclam)
      sub->add_option("--robot", req->robot, "robot number N (1 to 5)")->required();
    sub->callback([req] {
      const jobs::ImportOutcome o = jobs::run_import(*req);
      fmt::print("{}: {} rows, {:.3f} s, columns {}{}\n", req->output, o.rows, o.duration_s, o.columns,
                 o.no_commands_why ? "; velocity commands " + *o.no_commands_why : "");
    });
  }
  register_import_rosbag(*imp);
}

}  // namespace odotune::cli
