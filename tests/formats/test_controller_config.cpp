// The controller parameter files (odotune/formats/controller_config.h): for a known
// geometry, every kind's keys and values read back (YAML through yaml-cpp,
// the SDF element by a regex), both forms, the provenance comments at the
// top, and invalid input refused with nothing written.
#include <odotune/formats/controller_config.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <odotune/core/failure.h>

#include "support/cli_runner.h"
#include "support/temp_dir.h"

namespace odotune::formats {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
using testing_support::TempDir;

// Nominal 0.32 m wheels and 0.65 m base; calibrated R_L = 0.32·0.99,
// R_R = 0.32·1.012, D = 0.65·1.02 (the misaligned wheelchair of the
// calibration tests).
constexpr double kRNom = 0.32, kDNom = 0.65;
constexpr double kRL = 0.3168, kRR = 0.32384, kD = 0.663;
constexpr double kRMean = 0.5 * (kRL + kRR);  // 0.32032

ControllerGeometry known_geometry() {
  ControllerGeometry g;
  g.calibrated = {kRL, kRR, kD};
  g.nominal = {kRNom, kRNom, kDNom};
  g.nominal_source = "the first track's robot.* metadata";
  g.provenance = {"calibrated by odotune calibrate: method batch-pose", "tracks: a.csv, b--c.csv"};
  g.heldout = {"held-out position error 0.4120 m → 0.0310 m"};
  return g;
}

ControllerOptions options(ControllerKind kind, ControllerForm form = ControllerForm::multipliers) {
  ControllerOptions o;
  o.kind = kind;
  o.form = form;
  return o;
}

// The five parameters of a ROS file: their node, every key checked to be one
// of them, every value a number written with a decimal point (ROS 2 types
// `1` as an integer, which the controller's double parameters refuse).
std::map<std::string, double> ros_params(const YAML::Node& params) {
  const std::set<std::string> expected = {"wheel_separation", "wheel_radius", "wheel_separation_multiplier",
                                          "left_wheel_radius_multiplier", "right_wheel_radius_multiplier"};
  std::map<std::string, double> out;
  for (const auto& kv : params) {
    const std::string key = kv.first.as<std::string>();
    if (key == "type") continue;
    EXPECT_TRUE(expected.count(key)) << key;
    EXPECT_THAT(kv.second.Scalar(), HasSubstr(".")) << key;
    out[key] = kv.second.as<double>();
  }
  EXPECT_EQ(out.size(), expected.size());
  return out;
}

// The comment lines before the first line that is not a comment.
std::string leading_comments(const std::string& text, const std::string& prefix) {
  std::istringstream in(text);
  std::string out;
  for (std::string line; std::getline(in, line);) {
    if (line.empty()) continue;
    if (line.rfind(prefix, 0) != 0) break;
    out += line + "\n";
  }
  return out;
}

TEST(ControllerConfig, KindsAndFormsParseTheirKeysOnly) {
  for (ControllerKind k : {ControllerKind::ros2_control, ControllerKind::ros1, ControllerKind::gazebo}) {
    ControllerKind back = ControllerKind::gazebo == k ? ControllerKind::ros1 : ControllerKind::gazebo;
    ASSERT_TRUE(parse_controller_kind(to_string(k), &back)) << to_string(k);
    EXPECT_EQ(back, k);
  }
  EXPECT_EQ(to_string(ControllerKind::ros2_control), "ros2_control");
  EXPECT_EQ(to_string(ControllerKind::ros1), "ros1");
  EXPECT_EQ(to_string(ControllerKind::gazebo), "gazebo");
  ControllerKind k = ControllerKind::ros1;
  for (const char* bad : {"", "ros2", "ROS1", "gz", "gazebo "}) {
    EXPECT_FALSE(parse_controller_kind(bad, &k)) << bad;
    EXPECT_EQ(k, ControllerKind::ros1) << "untouched";
  }
  ControllerForm f = ControllerForm::absolute;
  ASSERT_TRUE(parse_controller_form("multipliers", &f));
  EXPECT_EQ(f, ControllerForm::multipliers);
  ASSERT_TRUE(parse_controller_form("absolute", &f));
  EXPECT_EQ(f, ControllerForm::absolute);
  EXPECT_FALSE(parse_controller_form("multiplier", &f));
  EXPECT_EQ(to_string(ControllerForm::multipliers), "multipliers");
}

TEST(ControllerConfig, Ros2MultipliersFormKeepsTheNominalAndScalesIt) {
  const std::string text = controller_config_text(known_geometry(), options(ControllerKind::ros2_control));
  const YAML::Node root = YAML::Load(text);
  ASSERT_TRUE(root.IsMap());
  EXPECT_EQ(root.size(), 1u);
  const YAML::Node params = root["diff_drive_controller"]["ros__parameters"];
  ASSERT_TRUE(params.IsMap()) << text;
  const auto p = ros_params(params);
  EXPECT_DOUBLE_EQ(p.at("wheel_separation"), kDNom);
  EXPECT_DOUBLE_EQ(p.at("wheel_radius"), kRNom);
  // 6 decimals: within 0.5e-6 of the exact ratios.
  EXPECT_NEAR(p.at("wheel_separation_multiplier"), 1.02, 5e-7);
  EXPECT_NEAR(p.at("left_wheel_radius_multiplier"), 0.99, 5e-7);
  EXPECT_NEAR(p.at("right_wheel_radius_multiplier"), 1.012, 5e-7);
  // The controller's products are the calibrated geometry (to 0.2 µm).
  EXPECT_NEAR(p.at("wheel_radius") * p.at("left_wheel_radius_multiplier"), kRL, 2e-7);
  EXPECT_NEAR(p.at("wheel_radius") * p.at("right_wheel_radius_multiplier"), kRR, 2e-7);
  EXPECT_NEAR(p.at("wheel_separation") * p.at("wheel_separation_multiplier"), kD, 4e-7);
  // The other form in the comments, with its values.
  const std::string head = leading_comments(text, "#");
  EXPECT_THAT(head, HasSubstr("absolute form"));
  EXPECT_THAT(head, HasSubstr("wheel_radius: 0.3203200"));
  EXPECT_THAT(head, HasSubstr("wheel_separation: 0.6630000"));
}

TEST(ControllerConfig, Ros2AbsoluteFormWritesTheCalibratedGeometry) {
  const std::string text = controller_config_text(known_geometry(), options(ControllerKind::ros2_control,
                                                                            ControllerForm::absolute));
  const auto p = ros_params(YAML::Load(text)["diff_drive_controller"]["ros__parameters"]);
  EXPECT_NEAR(p.at("wheel_separation"), kD, 5e-8);
  EXPECT_NEAR(p.at("wheel_radius"), kRMean, 5e-8);
  EXPECT_DOUBLE_EQ(p.at("wheel_separation_multiplier"), 1.0);
  EXPECT_NEAR(p.at("left_wheel_radius_multiplier"), kRL / kRMean, 5e-7);
  EXPECT_NEAR(p.at("right_wheel_radius_multiplier"), kRR / kRMean, 5e-7);
  const std::string head = leading_comments(text, "#");
  EXPECT_THAT(head, HasSubstr("multipliers form"));
  EXPECT_THAT(head, HasSubstr("wheel_separation_multiplier: 1.020000"));
  EXPECT_THAT(head, HasSubstr("left_wheel_radius_multiplier: 0.990000"));
  EXPECT_THAT(head, HasSubstr("wheel_radius: 0.3200000"));
  // controller_values gives the same numbers as the file.
  const ControllerValues v = controller_values(known_geometry(), ControllerForm::absolute);
  EXPECT_DOUBLE_EQ(v.wheel_radius_m, kRMean);
  EXPECT_DOUBLE_EQ(v.wheel_separation_m, kD);
}

TEST(ControllerConfig, Ros1HasTheTypeAndTheKeysUnderTheControllerName) {
  ControllerOptions o = options(ControllerKind::ros1);
  o.controller_name = "mobile_base_controller";
  const std::string text = controller_config_text(known_geometry(), o);
  const YAML::Node root = YAML::Load(text);
  EXPECT_EQ(root.size(), 1u);
  const YAML::Node c = root["mobile_base_controller"];
  ASSERT_TRUE(c.IsMap()) << text;
  EXPECT_EQ(c["type"].as<std::string>(), "diff_drive_controller/DiffDriveController");
  EXPECT_FALSE(c["ros__parameters"]) << "ROS 1 has no ros__parameters level";
  const auto p = ros_params(c);
  EXPECT_DOUBLE_EQ(p.at("wheel_radius"), kRNom);
  EXPECT_NEAR(p.at("right_wheel_radius_multiplier"), 1.012, 5e-7);
  // ros_controllers: wheel_radius_multiplier replaces both; the file says not to set it.
  EXPECT_THAT(leading_comments(text, "#"), HasSubstr("wheel_radius_multiplier"));
}

TEST(ControllerConfig, GazeboGetsTheMeanRadiusAndSaysTheDifferenceIsLost) {
  // The form does not matter for Gazebo: the absolute geometry either way.
  for (ControllerForm form : {ControllerForm::multipliers, ControllerForm::absolute}) {
    const std::string text = controller_config_text(known_geometry(), options(ControllerKind::gazebo, form));
    const auto element = [&](const std::string& name) {
      const std::regex re("<" + name + R"(>\s*([-+0-9.eE]+)\s*</)" + name + ">");
      std::vector<double> values;
      for (auto it = std::sregex_iterator(text.begin(), text.end(), re); it != std::sregex_iterator(); ++it)
        values.push_back(std::stod((*it)[1]));
      return values;
    };
    const std::vector<double> sep = element("wheel_separation"), radius = element("wheel_radius");
    ASSERT_EQ(sep.size(), 1u) << text;
    ASSERT_EQ(radius.size(), 1u) << text;
    EXPECT_NEAR(sep[0], kD, 5e-8);
    EXPECT_NEAR(radius[0], kRMean, 5e-8);
    EXPECT_THAT(text, HasSubstr("<plugin filename=\"gz-sim-diff-drive-system\" "
                                "name=\"gz::sim::systems::DiffDrive\">"));
    EXPECT_THAT(text, HasSubstr("</plugin>"));
    EXPECT_THAT(text, Not(HasSubstr("multiplier>")));
    // The lost difference, plainly, with its size: R_R − R_L = 7.04 mm, 2.198 % of the mean.
    EXPECT_THAT(text, HasSubstr("cannot be represented"));
    EXPECT_THAT(text, HasSubstr("+0.0070400 m"));
    EXPECT_THAT(text, HasSubstr("+2.198 %"));
    // Well-formed comments: no "--" inside one (the provenance had "b--c.csv").
    const std::regex comment("<!--(.*?)-->");
    int comments = 0;
    for (auto it = std::sregex_iterator(text.begin(), text.end(), comment); it != std::sregex_iterator();
         ++it) {
      EXPECT_EQ((*it)[1].str().find("--"), std::string::npos) << (*it)[0];
      ++comments;
    }
    EXPECT_GT(comments, 5);
    EXPECT_THAT(text, HasSubstr("b- -c.csv"));
  }
}

TEST(ControllerConfig, ProvenanceAndHeldOutLinesAreCommentsAtTheTop) {
  for (ControllerKind k : {ControllerKind::ros2_control, ControllerKind::ros1, ControllerKind::gazebo}) {
    const std::string text = controller_config_text(known_geometry(), options(k));
    const std::string head = leading_comments(text, k == ControllerKind::gazebo ? "<!--" : "#");
    for (const char* line : {"calibrated by odotune calibrate: method batch-pose", "tracks: a.csv",
                             "held-out position error 0.4120 m → 0.0310 m",
                             "calibrated geometry: R_L = 0.3168000 m, R_R = 0.3238400 m, D = 0.6630000 m",
                             "nominal (the first track's robot.* metadata): R_L = 0.3200000 m"})
      EXPECT_THAT(head, HasSubstr(line)) << to_string(k);
    EXPECT_THAT(head, HasSubstr("change against the nominal: left radius ×0.990000, right radius ×1.012000, "
                                "wheel base ×1.020000"))
        << to_string(k);
  }
}

TEST(ControllerConfig, UnequalNominalRadiiGiveTheirMeanAsWheelRadius) {
  ControllerGeometry g = known_geometry();
  g.nominal.wheel_radius_left_m = 0.31;
  g.nominal.wheel_radius_right_m = 0.33;
  const std::string text = controller_config_text(g, options(ControllerKind::ros2_control));
  const auto p = ros_params(YAML::Load(text)["diff_drive_controller"]["ros__parameters"]);
  EXPECT_DOUBLE_EQ(p.at("wheel_radius"), 0.32);
  EXPECT_NEAR(p.at("wheel_radius") * p.at("left_wheel_radius_multiplier"), kRL, 2e-7);
  EXPECT_NEAR(p.at("wheel_radius") * p.at("right_wheel_radius_multiplier"), kRR, 2e-7);
  EXPECT_THAT(text, HasSubstr("the nominal radii differ"));
  EXPECT_THAT(text, HasSubstr("left radius ×1.021935"));  // 0.3168 / 0.31
}

TEST(ControllerConfig, InvalidInputIsRefusedAndNothingIsWritten) {
  TempDir tmp;
  const auto path = tmp / "ddc.yaml";
  const auto expect_refused = [&](const ControllerGeometry& g, const ControllerOptions& o,
                                  const std::string& needle) {
    try {
      write_controller_config(g, o, path);
      ADD_FAILURE() << "accepted: " << needle;
    } catch (const core::Failure& e) {
      EXPECT_THAT(e.what(), HasSubstr(needle));
      EXPECT_THAT(e.what(), HasSubstr("ddc.yaml: not written"));
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "one line";
    }
    EXPECT_EQ(tmp.entries(), 0u) << needle;
  };
  const ControllerOptions ros2 = options(ControllerKind::ros2_control);
  ControllerGeometry no_nominal = known_geometry();
  no_nominal.nominal = {};
  expect_refused(no_nominal, ros2, "nominal");
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  for (double bad : {-0.3, 0.0, nan, inf}) {
    ControllerGeometry g = known_geometry();
    g.calibrated.wheel_radius_right_m = bad;
    expect_refused(g, ros2, "calibrated wheel_radius_right_m");
    g = known_geometry();
    g.nominal.wheel_base_m = bad;
    expect_refused(g, options(ControllerKind::gazebo), "nominal wheel_base_m");
  }
  ControllerGeometry broken = known_geometry();
  broken.provenance.push_back("two\nlines");
  expect_refused(broken, ros2, "line break");
  for (const char* name : {"", "1controller", "my controller", "a:b", "ddc#x"}) {
    ControllerOptions o = ros2;
    o.controller_name = name;
    expect_refused(known_geometry(), o, "controller_name");
  }
  ControllerOptions ok = ros2;
  ok.controller_name = "robot1/diff_drive_controller";
  EXPECT_TRUE(ok.IsValid(nullptr));

  // A good write: exactly the text, and nothing else beside it (no temporary).
  write_controller_config(known_geometry(), ros2, path);
  EXPECT_EQ(testing_support::slurp(path), controller_config_text(known_geometry(), ros2));
  EXPECT_EQ(tmp.entries(), 1u);
}

}  // namespace
}  // namespace odotune::formats
