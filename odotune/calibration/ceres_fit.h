// What the offline calibration fits (batch_calibration.h, pose_calibration.h)
// share around Ceres: standard errors of a
// parameter block (3 entries, or n) from ceres::Covariance scaled by the residual variance
// per degree of freedom.
#pragma once

#include <array>
#include <vector>

#include <ceres/ceres.h>

namespace odotune::calibration {

// The sds of the 3-vector parameter block `theta` after a solve: the
// covariance of the (whitened) problem scaled by s² = 2·final_cost/dof, so
// that they stay honest when the residuals' given variances are off. NaN for
// every entry when dof ≤ 0 or the Jacobian is rank deficient (judged on JᵀJ
// restricted to theta and scaled to a unit diagonal, before ceres::Covariance,
// which would log an error on a singular problem), e.g. D on a track that
// never turns.
std::array<double, 3> scaled_standard_errors(ceres::Problem& problem, double* theta, double final_cost,
                                             double dof);
// The same for a block of n entries.
std::vector<double> scaled_standard_errors(ceres::Problem& problem, double* theta, int n, double final_cost,
                                           double dof);

}  // namespace odotune::calibration
