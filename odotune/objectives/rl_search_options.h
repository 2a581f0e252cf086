// How the robot_localization tune searches its objective (odotune/jobs/rl_search.h
// runs the stages): read by the command line and by experiment files.
#pragma once

#include <string>
#include <vector>

namespace odotune::objectives {

struct RlSearchOptions {
  std::vector<double> grid_levels = {-2.0, 0.0, 2.0};  // decades; empty: no grid (refine around the file)
  double refine_decades = 0.0;                         // the seeded refinement's reach; 0: none
  double profile_step_decades = 0.5;
  double tolerance = 0.02;  // relative: "within 2 % of the best"
  bool profile = true;

  bool IsValid(std::string* why) const;
};

}  // namespace odotune::objectives
