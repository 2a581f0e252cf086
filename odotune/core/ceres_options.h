// The Ceres solver options of every deterministic fit (calibration's batch
// fits, the diagnosis's effect fits and gyro check): dense QR and one thread,
// so results never depend on the machine, silent, and the tolerances of a
// preset. Header-only; include it only from modules that link Ceres::ceres.
#pragma once

#include <ceres/ceres.h>

namespace odotune::core {

// Function and parameter tolerance; the gradient tolerance is a hundredth.
enum class FitTolerance {
  calibration,  // 1e-12: the calibration fits' few parameters to well below their errors
  diagnosis,    // 1e-10: the diagnosis's fits, stable to well below their standard errors
};

inline double fit_tolerance(FitTolerance preset) {
  switch (preset) {
    case FitTolerance::calibration: return 1e-12;
    case FitTolerance::diagnosis: return 1e-10;
  }
  return 1e-10;
}

inline ceres::Solver::Options deterministic_solver_options(int max_iterations, FitTolerance preset) {
  const double tol = fit_tolerance(preset);
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = max_iterations;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  so.function_tolerance = tol;
  so.gradient_tolerance = tol * 1e-2;
  so.parameter_tolerance = tol;
  return so;
}

}  // namespace odotune::core
