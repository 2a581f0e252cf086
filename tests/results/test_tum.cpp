// TUM trajectories (odotune/results/tum.h): the lines evo reads, read back to the
// poses (heading from the quaternion), the time offset, and an atomic write.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <odotune/results/tum.h>

#include "support/temp_dir.h"

namespace odotune::results {
namespace {

TEST(Tum, LinesReadBackToThePoses) {
  testing_support::TempDir dir;
  const auto path = dir.path() / "traj.tum";
  const std::vector<objectives::TrajectoryPoint> pts = {
      {0.0, 1.0, 2.0, 0.0}, {0.5, 1.5, 2.25, 2.5}, {1.0, -3.0, 0.5, -3.0}};
  write_tum(path, pts, "a test", 100.0);
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "# a test");
  std::getline(in, line);  // the column comment
  for (const auto& p : pts) {
    ASSERT_TRUE(std::getline(in, line));
    std::istringstream ss(line);
    double t, x, y, z, qx, qy, qz, qw;
    ss >> t >> x >> y >> z >> qx >> qy >> qz >> qw;
    ASSERT_FALSE(ss.fail()) << line;
    EXPECT_NEAR(t, p.t_s + 100.0, 1e-9);
    EXPECT_NEAR(x, p.x_m, 1e-6);
    EXPECT_NEAR(y, p.y_m, 1e-6);
    EXPECT_EQ(z, 0.0);
    EXPECT_EQ(qx, 0.0);
    EXPECT_EQ(qy, 0.0);
    EXPECT_NEAR(qz * qz + qw * qw, 1.0, 1e-8);
    const double heading = 2.0 * std::atan2(qz, qw);
    EXPECT_NEAR(std::remainder(heading - p.theta_rad, 2.0 * M_PI), 0.0, 1e-8);
  }
  EXPECT_FALSE(std::getline(in, line));
  // A folder that does not exist: an error, and no file.
  EXPECT_THROW(write_tum(dir.path() / "no" / "t.tum", pts, "x"), std::runtime_error);
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "no"));
}

}  // namespace
}  // namespace odotune::results
