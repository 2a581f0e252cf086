// navsat_transform_node's projection of a fix (robot_localization's
// navsat_conversions.h LLtoUTM / UTMtoLL and navsat_transform.cpp, read for
// behaviour): the UTM grid through GeographicLib, whose UTMUPS the node itself
// calls, with the zone of its datum kept for every later fix.
#pragma once

#include <string>

namespace odotune::rlnode {

struct UtmPoint {
  double easting_m = 0.0, northing_m = 0.0;
  int zone = 0;  // 1 … 60
  bool north = true;
  double convergence_rad = 0.0;  // the grid's meridian convergence there
};

// (latitude, longitude) [deg] on the UTM grid, in `zone` (−1: the point's
// standard zone). Throws std::invalid_argument for a point the grid does not cover.
UtmPoint utm_forward(double latitude_deg, double longitude_deg, int zone = -1);

// The inverse: (latitude, longitude) [deg] of a grid point.
void utm_reverse(const UtmPoint& p, double* latitude_deg, double* longitude_deg);

// The grid zone designator, zone and latitude band ("31U"), as LLtoUTM names it.
std::string utm_zone_designator(double latitude_deg, double longitude_deg);

}  // namespace odotune::rlnode
