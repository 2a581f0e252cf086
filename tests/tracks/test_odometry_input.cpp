// What a track's odometry is (odotune/tracks/odometry_input.h, docs/track-format.md's
// source.body_velocity) and its body velocities under the zero-order hold
// (odotune/tracks/body_velocity.h).
#include <sstream>
#include <stdexcept>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <odotune/tracks/body_velocity.h>
#include <odotune/tracks/odometry_input.h>
#include <odotune/tracks/track_io.h>

namespace odotune::tracks {
namespace {

using ::testing::HasSubstr;

Track parse_body(const std::string& meta, const std::string& rows = "0,0.5,0.1\n1,1.0,-0.2\n3,0,0\n") {
  std::istringstream in("# format: odotune-track/1\n# name: body\n" + meta + "t,v_cmd,w_cmd\n" + rows);
  return parse_track(in, "body.csv");
}

std::string input_error_of(const Track& t, std::optional<OdometryInput> requested) {
  try {
    track_odometry_input(t, requested);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(BodyVelocityMetadata, ReadWrittenAndRefusedByName) {
  const Track c = parse_body("# source.body_velocity: commanded\n");
  ASSERT_TRUE(c.meta().body_velocity.has_value());
  EXPECT_EQ(*c.meta().body_velocity, BodyVelocitySource::commanded);
  std::ostringstream out;
  format_track(c, out);
  EXPECT_THAT(out.str(), HasSubstr("# source.body_velocity: commanded\n"));
  std::istringstream back(out.str());
  EXPECT_EQ(*parse_track(back, "again.csv").meta().body_velocity, BodyVelocitySource::commanded);
  EXPECT_FALSE(parse_body("").meta().body_velocity.has_value());
  try {
    parse_body("# source.body_velocity: estimated\n");
    FAIL() << "expected an error";
  } catch (const TrackError& e) {
    EXPECT_EQ(e.line(), 3u);
    EXPECT_THAT(e.reason(), HasSubstr("'commanded' or 'measured'"));
  }
  try {
    parse_body("# source.body_velocity: measured\n# source.body_velocity: measured\n");
    FAIL() << "expected an error";
  } catch (const TrackError& e) {
    EXPECT_THAT(e.reason(), HasSubstr("duplicate"));
  }
}

TEST(OdometryInput, TheTrackSaysOrTheCallerChooses) {
  EXPECT_EQ(track_odometry_input(parse_body("# source.body_velocity: measured\n")), OdometryInput::twist);
  EXPECT_EQ(track_odometry_input(parse_body("# source.body_velocity: commanded\n")), OdometryInput::commands);
  const Track unsaid = parse_body("");
  EXPECT_THAT(input_error_of(unsaid, std::nullopt), HasSubstr("source.body_velocity"));
  EXPECT_THAT(input_error_of(unsaid, std::nullopt), HasSubstr("track 'body'"));
  EXPECT_EQ(track_odometry_input(unsaid, OdometryInput::twist), OdometryInput::twist);
  EXPECT_THAT(input_error_of(parse_body("# source.body_velocity: measured\n"), OdometryInput::commands),
              HasSubstr("contradicts"));
  EXPECT_THAT(input_error_of(unsaid, OdometryInput::wheels), HasSubstr("--input wheels"));
  OdometryInput in{};
  EXPECT_TRUE(parse_odometry_input("commands", &in));
  EXPECT_EQ(in, OdometryInput::commands);
  EXPECT_FALSE(parse_odometry_input("lidar", &in));
}

TEST(OdometryInput, WheelsComeFirstAndCommandsBesideThemCanBeChosen) {
  std::istringstream in(
      "# format: odotune-track/1\n# robot.ticks_per_rev: 100\n# robot.wheel_radius_left: 0.1\n"
      "# robot.wheel_radius_right: 0.1\n# robot.wheel_base: 0.5\n# source.body_velocity: commanded\n"
      "t,ticks_l,ticks_r,v_cmd,w_cmd\n0,0,0,0.1,0\n1,10,12,0.1,0\n");
  const Track t = parse_track(in, "both.csv");
  EXPECT_EQ(track_odometry_input(t), OdometryInput::wheels);
  EXPECT_EQ(track_odometry_input(t, OdometryInput::commands), OdometryInput::commands);
}

// Each sample holds until the next; the last closes the span.
TEST(BodyVelocityIntegral, ZeroOrderHoldIntegralsAndDelayedMeans) {
  const BodyVelocityIntegral b(parse_body("", "0,0.5,0.1\n1,1.0,-0.2\n3,0,0\n"));
  ASSERT_EQ(b.size(), 3u);
  EXPECT_DOUBLE_EQ(b.at(-1.0)[0], 0.0);
  EXPECT_DOUBLE_EQ(b.at(0.5)[0], 0.25);
  EXPECT_DOUBLE_EQ(b.at(2.0)[0], 0.5 + 1.0);
  EXPECT_DOUBLE_EQ(b.at(2.0)[1], 0.1 - 0.2);
  EXPECT_DOUBLE_EQ(b.at(9.0)[0], 0.5 + 2.0);
  // Over (0.5, 1.5]: half a second of each sample.
  EXPECT_DOUBLE_EQ(b.mean(0.5, 1.5)[0], 0.75);
  // Delayed by 0.5 s: the input over (0, 1], the first sample only.
  EXPECT_DOUBLE_EQ(b.mean(0.5, 1.5, 0.5)[0], 0.5);
  EXPECT_DOUBLE_EQ(b.mean(0.5, 1.5, 0.5)[1], 0.1);
}

}  // namespace
}  // namespace odotune::tracks
