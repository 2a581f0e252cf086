#include <odotune/results/tum.h>

#include <cmath>
#include <ostream>

#include <fmt/format.h>

#include <odotune/core/atomic_file.h>

namespace odotune::results {

void write_tum(const std::filesystem::path& path, const std::vector<objectives::TrajectoryPoint>& points,
               const std::string& comment, double time_offset_s) {
  core::write_atomically(path, "trajectory", [&](std::ostream& out) {
    out << "# " << comment << "\n# t x y z qx qy qz qw (TUM format; z = 0, rotation about z by the heading)\n";
    for (const objectives::TrajectoryPoint& p : points)
      out << fmt::format("{:.9f} {:.6f} {:.6f} 0 0 0 {:.9f} {:.9f}\n", p.t_s + time_offset_s, p.x_m, p.y_m,
                         std::sin(0.5 * p.theta_rad), std::cos(0.5 * p.theta_rad));
  });
}

}  // namespace odotune::results
