#include <odotune/rlnode/geodesy.h>

#include <numbers>
#include <stdexcept>

#include <GeographicLib/MGRS.hpp>
#include <GeographicLib/UTMUPS.hpp>
#include <fmt/format.h>

namespace odotune::rlnode {

UtmPoint utm_forward(double latitude_deg, double longitude_deg, int zone) {
  UtmPoint p;
  double gamma_deg = 0.0, k = 1.0;
  try {
    GeographicLib::UTMUPS::Forward(latitude_deg, longitude_deg, p.zone, p.north, p.easting_m, p.northing_m,
                                   gamma_deg, k, zone < 0 ? GeographicLib::UTMUPS::STANDARD : zone);
  } catch (const GeographicLib::GeographicErr& e) {
    throw std::invalid_argument(fmt::format("latitude {} °, longitude {} °: not on the UTM grid ({})",
                                            latitude_deg, longitude_deg, e.what()));
  }
  p.convergence_rad = gamma_deg * std::numbers::pi / 180.0;
  return p;
}

void utm_reverse(const UtmPoint& p, double* latitude_deg, double* longitude_deg) {
  GeographicLib::UTMUPS::Reverse(p.zone, p.north, p.easting_m, p.northing_m, *latitude_deg, *longitude_deg);
}

std::string utm_zone_designator(double latitude_deg, double longitude_deg) {
  const UtmPoint p = utm_forward(latitude_deg, longitude_deg);
  std::string mgrs;
  // Precision −1: the grid zone designation alone.
  GeographicLib::MGRS::Forward(p.zone, p.north, p.easting_m, p.northing_m, latitude_deg, -1, mgrs);
  return mgrs;
}

}  // namespace odotune::rlnode
