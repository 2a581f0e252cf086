// Two copies of one online calibrator (PfCalibrator with the evidence
// evolution, DualKf with fading memory) that differ only in their memory
// (odotune/filters/pf_evolution.h): `slow`, whose memory grows from min_memory_s to
// max_memory_s (the running mean of all the evidence since the last change:
// a static robot's estimate keeps sharpening), and `fast`, whose memory stays
// at min_memory_s (it follows a change within about that time, and is
// noisier when nothing changes). The reported estimate is the slow one's.
//
// Change test: Page's CUSUM of the log-likelihood ratio of their predictive
// densities, C_k = max(0, C_{k−1} + log p_fast(y_k) − log p_slow(y_k)) (E. S.
// Page, "Continuous inspection schemes", Biometrika 41, 1954; the fast twin
// plays the post-change model, as in generalised-likelihood-ratio
// detectors). Without a change the slow filter predicts better and C stays
// near 0; after one (a passenger boards: the radii drop 1 %) the fast twin
// adapts first, predicts better, and C climbs. When C exceeds
// cusum_threshold (a log Bayes factor), the slow filter takes the fast one's
// state, restarts its memory, and C restarts. A transient mismatch that
// reverts (wheel slip in a spin) gives the fast twin a brief edge that its
// extra noise then gives back, so a long-memory estimate survives it.
//
// Both copies draw the same random numbers (same seed, common random
// numbers), so the ratio measures the memories, not the draws; same seed ⇒
// same estimates with any thread count, as for the filter alone.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

#include <odotune/core/why.h>
#include <odotune/filters/odometry_params.h>
#include <odotune/filters/pf_evolution.h>

namespace odotune::filters {

struct MemoryPairParams {
  // log Bayes factor of a change (e^5 ≈ 150 : 1). Chosen on the simulated
  // wheelchair studies (docs/calibration/README.md: 3 and 5 keep their step
  // tracking, 10 loses it for the DKF), never on the real recordings the
  // docs report.
  double cusum_threshold = 5.0;

  bool IsValid(std::string* why) const {
    if (cusum_threshold > 0.0) return true;  // +inf: never a change
    return core::invalid(why, "cusum_threshold = " + std::to_string(cusum_threshold) + " must be > 0");
  }
};

// The fast twin's memory: fixed at the slow one's minimum.
inline EvidenceMemoryParams fast_twin(const EvidenceMemoryParams& p) {
  return {p.min_memory_s, p.min_memory_s};
}

// Memory: the filter's memory parameters (EvidenceMemoryParams, in seconds;
// odotune/filters/pose_calibrator.h's DistanceMemoryParams, in metres), with a
// fast_twin() overload.
template <class Filter, class Memory = EvidenceMemoryParams>
class MemoryPair {
 public:
  // `proto` is the filter as configured (its own memory is replaced).
  MemoryPair(const Filter& proto, const Memory& memory, const MemoryPairParams& pair)
      : memory_(memory), pair_(pair), slow_(proto), fast_(proto) {
    slow_.set_memory(memory_);
    fast_.set_memory(fast_twin(memory_));
  }

  // Sample: what Filter::step takes (CalibSample, or PoseCalibSample for
  // odotune/filters/pose_calibrator.h, whose log predictive is 0 between fixes).
  template <class Sample>
  const CalibEstimate& step(const Sample& s) {
    fast_.step(s);
    slow_.step(s);
    const double llr = fast_.last_log_predictive() - slow_.last_log_predictive();
    if (std::isfinite(llr)) cusum_ = std::max(0.0, cusum_ + llr);
    if (cusum_ > pair_.cusum_threshold) {
      slow_ = fast_;
      slow_.set_memory(memory_);
      cusum_ = 0.0;
      ++changes_;
    }
    return slow_.estimate();
  }

  const CalibEstimate& estimate() const { return slow_.estimate(); }
  long iterations() const { return slow_.iterations(); }
  long changes() const { return changes_; }
  double cusum() const { return cusum_; }
  const Filter& slow() const { return slow_; }
  const Filter& fast() const { return fast_; }
  // Calls fn on both copies (e.g. to restart the pose of a new run).
  template <class Fn>
  void apply(Fn&& fn) {
    fn(slow_);
    fn(fast_);
  }

 private:
  Memory memory_;
  MemoryPairParams pair_;
  Filter slow_, fast_;
  double cusum_ = 0.0;
  long changes_ = 0;
};

}  // namespace odotune::filters
