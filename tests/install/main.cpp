// Uses odotune from its installed package: a PSO minimisation (tuner/) and an
// EKF step (filters/), beside a header of its own named filters/ekf.h. Exits 1 with a line on stderr when a result is wrong, so
// the ctest Install.OutsideProjectFindsOdotune fails on a broken install.
#include <cmath>
#include <cstdio>
#include <span>

#include <odotune/filters/ekf.h>
#include <odotune/tuner/pso.h>

#include "filters/ekf.h"  // the consumer's own header of the same name

namespace {

// (x − 1.5)² + (y + 0.5)², minimum 0 at (1.5, −0.5).
struct Quadratic {
  double fitness(std::span<const double> x) const {
    return (x[0] - 1.5) * (x[0] - 1.5) + (x[1] + 0.5) * (x[1] + 0.5);
  }
  odotune::tuner::Bounds bounds() const { return {{-5.0, -5.0}, {5.0, 5.0}}; }
};

bool check(bool ok, const char* what) {
  if (!ok) std::fprintf(stderr, "consumer: %s\n", what);
  return ok;
}

}  // namespace

int main() {
  odotune::tuner::PsoOptions pso;
  pso.particles = 20;
  pso.iterations = 60;
  pso.seed = 1;
  const odotune::tuner::Summary s = odotune::tuner::pso_minimize(Quadratic{}, pso);
  std::printf("pso: best (%.6f, %.6f), fitness %.3g after %ld evaluations\n", s.best_x.at(0), s.best_x.at(1),
              s.best_fitness, static_cast<long>(s.evaluations));

  odotune::filters::EkfParams params;
  params.noise.a1 = 0.01;
  params.noise.a2 = 0.01;
  odotune::filters::Ekf ekf(params);
  ekf.predict({1.0, 1.0}, 0.0);  // both wheels 1 m: straight ahead along x
  const double var_x_after_predict = ekf.cov()(0, 0);
  ekf.update(odotune::filters::Position(1.02, 0.0));
  std::printf("ekf: pose (%.4f, %.4f, %.4f), var x %.3g → %.3g after a fix\n", ekf.pose()(0), ekf.pose()(1),
              ekf.pose()(2), var_x_after_predict, ekf.cov()(0, 0));

  bool ok = check(s.ok(), "PSO failed");
  ok &= check(s.best_x.size() == 2 && std::abs(s.best_x[0] - 1.5) < 1e-3 && std::abs(s.best_x[1] + 0.5) < 1e-3,
              "PSO did not find the quadratic's minimum (1.5, -0.5)");
  ok &= check(s.best_fitness < 1e-6, "PSO's best fitness is not ~0");
  ok &= check(var_x_after_predict > params.initial_cov(0, 0), "the prediction did not add process noise");
  ok &= check(ekf.pose()(0) > 1.0 && ekf.pose()(0) < 1.02 && std::abs(ekf.pose()(1)) < 1e-12,
              "the fix did not pull x between the prediction (1.0) and the fix (1.02)");
  ok &= check(ekf.cov()(0, 0) < var_x_after_predict, "the fix did not shrink the x variance");
  ok &= check(ekf.check() == odotune::filters::Divergence::none, "the filter diverged");
  ok &= check(consumer::smooth(1.0, 3.0, 0.5) == 2.0,
              "the consumer's own filters/ekf.h was not the one included");
  if (!ok) return 1;
  std::printf("consumer: ok\n");
  return 0;
}
