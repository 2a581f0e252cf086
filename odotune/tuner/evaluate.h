// A list of points evaluated, in parallel (OpenMP): the deterministic stages of
// a search (a grid, a profile) that need no solver. The values are the
// problem's own, in the points' order, whatever the thread count.
#pragma once

#include <atomic>
#include <vector>

#include <odotune/tuner/problem.h>

namespace odotune::tuner {

// fitness(points[i]) for every i, batch_size() points per call for a batch
// problem. Rethrows the first exception a fitness threw (in the points'
// order) once the loop is done. With `stop` raised, the points not yet
// started are left as NaN. All points have the box's dimension.
std::vector<double> evaluate_all(ProblemRef problem, const std::vector<std::vector<double>>& points,
                                 const std::atomic<bool>* stop = nullptr);

}  // namespace odotune::tuner
