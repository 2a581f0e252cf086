// The Ceres solver options every fit of the diagnosis uses (fit.h,
// gyro_fixes_check.h): dense QR, one thread (so results never depend on the
// machine), silent, and tolerances tight enough that the fitted parameters
// are stable to well below their standard errors.
#pragma once

#include <ceres/ceres.h>

namespace odotune::diagnose {

inline ceres::Solver::Options diagnosis_solver_options(int max_iterations) {
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = max_iterations;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  so.function_tolerance = 1e-10;
  so.gradient_tolerance = 1e-12;
  so.parameter_tolerance = 1e-10;
  return so;
}

}  // namespace odotune::diagnose
