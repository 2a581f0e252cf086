// Tests of the robot_localization (ROS 2 ekf_node) parameter-file export.
#include <odotune/results/ros_export.h>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>

#include "support/cli_runner.h"
#include "support/temp_dir.h"

namespace odotune::results {
namespace {

using testing_support::TempDir;

namespace fs = std::filesystem;

// robot_localization's default process_noise_covariance diagonal, typed in
// from cra-ros-pkg/robot_localization src/filter_base.cpp FilterBase::reset()
// (independently of the constant in ros_export.cpp).
constexpr double kDefaults[15] = {0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025,
                                  0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015};

RosExportInput awkward_input() {
  RosExportInput in;
  in.node_name = "my_ekf";
  in.process_var_x_m2_per_s = 1.234567890123e-3;
  in.process_var_y_m2_per_s = 0.1 / 3.0;
  in.process_var_yaw_rad2_per_s = 7.77e-9;
  in.fix_var_x_m2 = 3.6e-3;
  in.fix_var_y_m2 = 2.5e-3;
  in.frequency_hz = 47.5;
  in.two_d_mode = false;
  in.provenance = "odotune tune: model rq, mode 7, seed 1, track1";
  in.tuned_params = {{"r1_mm2", 24.69}, {"r2_mm2", 666.7}};
  return in;
}

void expect_rel_near(double expected, double actual, double rel) {
  EXPECT_NEAR(actual, expected, rel * std::abs(expected)) << "expected " << expected;
}

std::string message_of(const std::string& text) {
  try {
    parse_robot_localization_yaml(text);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no exception for:\n" << text;
  return "";
}

std::string replace_once(std::string s, const std::string& from, const std::string& to) {
  const auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) s.replace(pos, from.size(), to);
  return s;
}

TEST(RosExport, RoundTripPreservesTunedDiagonalDefaultsAndZeros) {
  const RosExportInput in = awkward_input();
  const RosExportParsed p = parse_robot_localization_yaml(robot_localization_yaml(in));
  EXPECT_EQ(p.node_name, "my_ekf");
  EXPECT_EQ(p.frequency_hz, 47.5);
  EXPECT_FALSE(p.two_d_mode);
  expect_rel_near(in.process_var_x_m2_per_s, p.at(0, 0), 1e-12);
  expect_rel_near(in.process_var_y_m2_per_s, p.at(1, 1), 1e-12);
  expect_rel_near(in.process_var_yaw_rad2_per_s, p.at(5, 5), 1e-12);
  for (int i = 0; i < 15; ++i) {
    for (int j = 0; j < 15; ++j) {
      if (i != j) {
        EXPECT_EQ(p.at(i, j), 0.0) << i << "," << j;
      } else if (i != 0 && i != 1 && i != 5) {
        EXPECT_EQ(p.at(i, i), kDefaults[i]) << "state " << i;
      }
    }
  }
  // The other defaults and the two_d_mode = true case.
  RosExportInput in2 = in;
  in2.two_d_mode = true;
  in2.node_name = "ekf_filter_node";
  const RosExportParsed p2 = parse_robot_localization_yaml(robot_localization_yaml(in2));
  EXPECT_TRUE(p2.two_d_mode);
  EXPECT_EQ(p2.node_name, "ekf_filter_node");
}

TEST(RosExport, RqConversionPerStepToPerSecondAndMm2ToM2) {
  const RosExportInput in = ros_input_from_rq(100.0, 2500.0, 1e-4, 3600.0, 900.0, 50.0);
  // 100 mm² per step × 50 steps/s = 5000 mm²/s = 5e-3 m²/s.
  expect_rel_near(100e-6 * 50, in.process_var_x_m2_per_s, 1e-12);
  EXPECT_EQ(in.process_var_x_m2_per_s, 5e-3);  // one rounding only
  expect_rel_near(0.125, in.process_var_y_m2_per_s, 1e-12);
  expect_rel_near(5e-3, in.process_var_yaw_rad2_per_s, 1e-12);  // rad², no unit change
  expect_rel_near(3.6e-3, in.fix_var_x_m2, 1e-12);              // (60 mm)²
  expect_rel_near(9e-4, in.fix_var_y_m2, 1e-12);                // (30 mm)²
  EXPECT_EQ(in.frequency_hz, 50.0);
  ASSERT_EQ(in.tuned_params.size(), 5u);
  EXPECT_EQ(in.tuned_params[0].first, "r1_mm2");
  EXPECT_EQ(in.tuned_params[0].second, 100.0);
  EXPECT_EQ(in.tuned_params[2].first, "r3_rad2");
  EXPECT_EQ(in.tuned_params[4].first, "q2_mm2");

  // Same per-second growth at another rate: half the rate, double the rate-less value.
  const RosExportInput slow = ros_input_from_rq(100.0, 2500.0, 1e-4, 3600.0, 900.0, 25.0);
  expect_rel_near(2.5e-3, slow.process_var_x_m2_per_s, 1e-12);

  EXPECT_THROW(ros_input_from_rq(1, 1, 1, 1, 1, 0.0), std::invalid_argument);
  EXPECT_THROW(ros_input_from_rq(1, 1, 1, 1, 1, -5.0), std::invalid_argument);
  EXPECT_THROW(ros_input_from_rq(1, 1, 1, 1, 1, std::nan("")), std::invalid_argument);

  std::string why;
  EXPECT_TRUE(in.IsValid(&why)) << why;
}

TEST(RosExport, FileIsValidRos2YamlWithDoubleLiterals) {
  RosExportInput in = ros_input_from_rq(100.0, 100.0, 1e-4, 3600.0, 3600.0, 50.0);
  const std::string text = robot_localization_yaml(in);
  const YAML::Node root = YAML::Load(text);
  ASSERT_TRUE(root.IsMap());
  EXPECT_EQ(root.size(), 1u);
  const YAML::Node params = root["ekf_filter_node"]["ros__parameters"];
  ASSERT_TRUE(params && params.IsMap());
  // ROS 2 types a parameter from its literal: integers where robot_localization
  // declares doubles are rejected, so every number must look like a double.
  EXPECT_EQ(params["frequency"].Scalar(), "50.0");
  EXPECT_EQ(params["two_d_mode"].Scalar(), "true");
  const YAML::Node m = params["process_noise_covariance"];
  ASSERT_TRUE(m.IsSequence());
  ASSERT_EQ(m.size(), 225u);
  // YAML 1.1 float syntax (what PyYAML in ROS 2 launch accepts): '.' in the
  // mantissa, signed exponent.
  const std::regex yaml11_float(R"([-+]?[0-9]+\.[0-9]*([eE][-+][0-9]+)?)");
  for (std::size_t k = 0; k < m.size(); ++k)
    EXPECT_TRUE(std::regex_match(m[k].Scalar(), yaml11_float)) << k << ": " << m[k].Scalar();
  EXPECT_EQ(m[0].Scalar(), "0.005");  // 100 mm² × 50 Hz / 1e6, no 0.004999…
  // Tiny and huge values keep the float form.
  in.process_var_yaw_rad2_per_s = 1e-5;
  in.process_var_y_m2_per_s = 1e22;
  const YAML::Node m2 = YAML::Load(
      robot_localization_yaml(in))["ekf_filter_node"]["ros__parameters"]["process_noise_covariance"];
  EXPECT_EQ(m2[5 * 15 + 5].Scalar(), "1.0e-05");
  EXPECT_TRUE(std::regex_match(m2[1 * 15 + 1].Scalar(), yaml11_float)) << m2[16].Scalar();
  EXPECT_EQ(m2[1 * 15 + 1].as<double>(), 1e22);

  // Laid out as 15 rows of 15 numbers, each row labelled with its state.
  std::istringstream lines(text);
  std::string line;
  int rows = 0;
  const char* names[15] = {"x",  "y",     "z",      "roll", "pitch", "yaw", "vx", "vy",
                           "vz", "vroll", "vpitch", "vyaw", "ax",    "ay",  "az"};
  bool in_matrix = false;
  while (std::getline(lines, line)) {
    if (line.find("process_noise_covariance: [") != std::string::npos) {
      in_matrix = true;
      continue;
    }
    if (!in_matrix || rows >= 15) continue;
    const std::string data = line.substr(0, line.find('#'));
    int numbers = 0;
    std::istringstream cells(data);
    std::string cell;
    while (std::getline(cells, cell, ',')) {
      if (cell.find_first_not_of(" ]") != std::string::npos) ++numbers;
    }
    EXPECT_EQ(numbers, 15) << line;
    EXPECT_NE(line.find(std::string("# ") + names[rows]), std::string::npos) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 15);
}

TEST(RosExport, CommentsExplainMappingConversionAndMeasurementCovariance) {
  RosExportInput in = ros_input_from_rq(100.0, 100.0, 1e-4, 3600.0, 2500.0, 50.0);
  in.provenance = "odotune tune: model rq, mode 7, seed 1, track1";
  const std::string text = robot_localization_yaml(in);
  for (const char* needle : {"odotune tune: model rq, mode 7, seed 1, track1", "r1_mm2 = 100", "q2_mm2 = 2500",
                             "odometry rate", "1e-6", "delta_sec", "src/ekf.cpp", "filter_base.cpp", "pose0",
                             "odom0", "covariance[0] (x, x) = 0.0036 m²", "covariance[7] (y, y) = 0.0025 m²",
                             "x, y, z, roll, pitch, yaw, vx, vy, vz, vroll, vpitch, vyaw, ax, ay, az"}) {
    EXPECT_NE(text.find(needle), std::string::npos) << "missing: " << needle << "\n" << text;
  }
}

TEST(RosExport, NewlinesInCommentsCannotInjectKeys) {
  RosExportInput in = awkward_input();
  in.provenance = "run 1\nevil: 1";
  in.tuned_params = {{"a\nevil2: 2", 1.0}};
  const YAML::Node root = YAML::Load(robot_localization_yaml(in));
  EXPECT_EQ(root.size(), 1u);
  EXPECT_FALSE(root["evil"]);
  EXPECT_FALSE(root["evil2"]);
}

TEST(RosExport, MappingNoteReplacesTheRqExplanationLineByLine) {
  RosExportInput in = awkward_input();
  const std::string rq_text = robot_localization_yaml(in);
  EXPECT_NE(rq_text.find("Mapping from odotune's rq model"), std::string::npos);

  in.mapping_note = "Mapping from the alpha model:\n  Q = mean R x rate\r\nevil: 3\nlast";
  const std::string text = robot_localization_yaml(in);
  EXPECT_EQ(text.find("Mapping from odotune's rq model"), std::string::npos) << text;
  EXPECT_EQ(text.find("r1 [mm²/step]"), std::string::npos) << text;
  for (const char* needle : {"\n# Mapping from the alpha model:\n", "\n#   Q = mean R x rate \n",
                             "\n# evil: 3\n", "\n# last\n", "Values here: Q[x][x]", "filter_base.cpp"})
    EXPECT_NE(text.find(needle), std::string::npos) << "missing: " << needle << "\n" << text;
  // Every line of the note is a comment: the YAML is unchanged.
  const YAML::Node root = YAML::Load(text);
  EXPECT_EQ(root.size(), 1u);
  EXPECT_FALSE(root["evil"]);
  const RosExportParsed a = parse_robot_localization_yaml(text), b = parse_robot_localization_yaml(rq_text);
  EXPECT_EQ(a.process_noise_covariance, b.process_noise_covariance);
  EXPECT_EQ(a.frequency_hz, b.frequency_hz);
}

TEST(RosExport, InvalidInputIsRejected) {
  const RosExportInput good = awkward_input();
  std::string why;
  ASSERT_TRUE(good.IsValid(&why)) << why;

  RosExportInput bad = good;
  bad.process_var_x_m2_per_s = -1.0;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("process_var_x_m2_per_s"), std::string::npos) << why;
  EXPECT_THROW(robot_localization_yaml(bad), std::invalid_argument);

  bad = good;
  bad.process_var_yaw_rad2_per_s = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("yaw"), std::string::npos) << why;

  bad = good;
  bad.fix_var_y_m2 = 0.0;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("fix_var_y_m2"), std::string::npos) << why;

  bad = good;
  bad.frequency_hz = std::nan("");
  EXPECT_FALSE(bad.IsValid(&why));

  bad = good;
  bad.node_name = "ekf: {x";
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("node_name"), std::string::npos) << why;
  bad.node_name = "";
  EXPECT_FALSE(bad.IsValid(&why));
}

TEST(RosExportErrors, MissingKeysAreNamed) {
  const std::string text = robot_localization_yaml(awkward_input());
  std::string msg = message_of(replace_once(text, "frequency: 47.5", "freq: 47.5"));
  EXPECT_NE(msg.find("missing key 'frequency'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("robot_localization YAML:"), std::string::npos) << msg;

  msg = message_of(replace_once(text, "two_d_mode: false", "other: false"));
  EXPECT_NE(msg.find("missing key 'two_d_mode'"), std::string::npos) << msg;

  msg = message_of(replace_once(text, "process_noise_covariance:", "initial_estimate_covariance:"));
  EXPECT_NE(msg.find("missing key 'process_noise_covariance'"), std::string::npos) << msg;

  msg = message_of(replace_once(text, "ros__parameters:", "parameters:"));
  EXPECT_NE(msg.find("ros__parameters"), std::string::npos) << msg;
}

TEST(RosExportErrors, MatrixOfWrongSizeOrContentIsExplained) {
  const std::string text = robot_localization_yaml(awkward_input());
  // Drop the final element: 224 numbers.
  const auto end = text.rfind(']');
  const auto prev = text.rfind(',', end);
  ASSERT_NE(prev, std::string::npos);
  const std::string short_text = text.substr(0, prev) + "]\n";
  std::string msg = message_of(short_text);
  EXPECT_NE(msg.find("has 224 numbers, expected 225"), std::string::npos) << msg;

  msg = message_of(text.substr(0, end) + ", 0.0]\n");
  EXPECT_NE(msg.find("has 226 numbers, expected 225"), std::string::npos) << msg;

  // A non-number in row 1, column 2 (same size).
  const auto first_zero = text.find("0.0,", text.find("process_noise_covariance: ["));
  ASSERT_NE(first_zero, std::string::npos);
  std::string bad_cell = text;
  bad_cell.replace(first_zero, 3, "abc");
  msg = message_of(bad_cell);
  EXPECT_NE(msg.find("element 1 (row 1, column 2) is 'abc', expected a number"), std::string::npos) << msg;
  EXPECT_NE(msg.find("robot_localization YAML:"), std::string::npos) << msg;

  msg = message_of("n:\n  ros__parameters:\n    frequency: 1.0\n    two_d_mode: true\n"
                   "    process_noise_covariance: 3.0\n");
  EXPECT_NE(msg.find("robot_localization YAML:5: 'process_noise_covariance' is not a list"), std::string::npos)
      << msg;
}

TEST(RosExportErrors, InvalidYamlAndWrongTypesGiveLineNumbers) {
  std::string msg = message_of("n:\n  ros__parameters:\n    frequency: [1.0\n");
  EXPECT_NE(msg.find("invalid YAML"), std::string::npos) << msg;
  msg = message_of("n:\n  ros__parameters:\n    frequency: fast\n    two_d_mode: true\n");
  EXPECT_NE(msg.find("robot_localization YAML:3: 'frequency' is 'fast', expected a number"), std::string::npos)
      << msg;
  msg = message_of("n:\n  ros__parameters:\n    frequency: 1.0\n    two_d_mode: maybe\n");
  EXPECT_NE(msg.find(":4: 'two_d_mode' is 'maybe', expected true or false"), std::string::npos) << msg;
  msg = message_of("- just a list\n");
  EXPECT_NE(msg.find("top level"), std::string::npos) << msg;
  EXPECT_THROW(parse_robot_localization_yaml(""), std::runtime_error);
}

using testing_support::slurp;

std::size_t entries(const fs::path& dir) {
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

TEST(RosExportWrite, WritesAtomicallyAndOverwrites) {
  TempDir dir;
  const fs::path out = dir.path() / "ekf.yaml";
  const RosExportInput in = awkward_input();
  write_robot_localization_yaml(in, out);
  EXPECT_EQ(slurp(out), robot_localization_yaml(in));
  EXPECT_EQ(entries(dir.path()), 1u);  // no temporary left behind

  RosExportInput in2 = in;
  in2.frequency_hz = 10.0;
  write_robot_localization_yaml(in2, out);
  EXPECT_EQ(parse_robot_localization_yaml(slurp(out)).frequency_hz, 10.0);
  EXPECT_EQ(entries(dir.path()), 1u);

  // Invalid input: throws, and the existing file is untouched.
  RosExportInput bad = in;
  bad.fix_var_x_m2 = -1.0;
  EXPECT_THROW(write_robot_localization_yaml(bad, out), std::invalid_argument);
  EXPECT_EQ(parse_robot_localization_yaml(slurp(out)).frequency_hz, 10.0);
  EXPECT_EQ(entries(dir.path()), 1u);
}

TEST(RosExportWrite, MissingDirectoryThrowsAndLeavesNothing) {
  TempDir dir;
  const fs::path out = dir.path() / "no-such-dir" / "ekf.yaml";
  try {
    write_robot_localization_yaml(awkward_input(), out);
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(out.string()), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(out.parent_path()));
  EXPECT_EQ(entries(dir.path()), 0u);

  // Target is a directory: the rename fails, the temporary is removed.
  const fs::path as_dir = dir.path() / "taken";
  fs::create_directories(as_dir / "child");
  EXPECT_THROW(write_robot_localization_yaml(awkward_input(), as_dir), std::runtime_error);
  EXPECT_EQ(entries(dir.path()), 1u);
  EXPECT_TRUE(fs::is_directory(as_dir / "child"));
}

}  // namespace
}  // namespace odotune::results
