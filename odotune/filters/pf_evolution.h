// Fading memory: how much an online calibrator (the PF's evidence evolution,
// pf_calibrator.h; the DKF's fading_memory, dual_kf.h) widens its parameter
// uncertainty before each measurement.
//
// A departure from Fariña, Toledo & Acosta (RA-L 2026, §III eq. 2–3 and §V
// eq. 11), whose random walk has a σ fixed in metres per iteration. On a slow
// robot (OptiOdom: 0.12 m/s, 42 mm wheels) one measurement says little about
// the radii, that walk outruns the evidence and the estimates drift to the
// edge of their range (docs/calibration/real-data.md). Here the widening is
// scaled to the evidence instead: each parameter's posterior variance is
// inflated by e^{dt/M} − 1 per measurement dt apart (exponential forgetting
// with time constant M), so the estimate weighs about the last M seconds of
// evidence, however much or little each measurement carries. M is the time
// since the memory (re)started, clamped to [min_memory_s, max_memory_s]:
// forgetting at rate 1/t is the running mean of all the evidence so far, so a
// robot whose parameters do not change gets an ever sharper estimate. A
// change (a passenger boards, a tyre loses pressure) is found by comparing
// this filter with a twin that always forgets fast (odotune/filters/memory_pair.h).
// The filters also never widen a parameter past its prior (bounded
// forgetting: a direction the drive does not excite cannot wind up).
#pragma once

#include <string>

namespace odotune::filters {

struct EvidenceMemoryParams {
  double min_memory_s = 10.0;    // M at the (re)start [s]; the fast twin's fixed M
  double max_memory_s = 1000.0;  // the longest memory [s]

  // True when usable; otherwise *why names the first bad value.
  bool IsValid(std::string* why) const;
};

class EvidenceMemory {
 public:
  explicit EvidenceMemory(const EvidenceMemoryParams& p = {}) : p_(p), memory_s_(p.min_memory_s) {}

  // The variance inflation e^{dt/M} − 1 for a measurement dt_s after the
  // previous one (0 for dt ≤ 0); then M grows by dt (up to max_memory_s).
  double step(double dt_s);
  // Starts again from min_memory_s.
  void restart() { memory_s_ = p_.min_memory_s; }

  double memory_s() const { return memory_s_; }
  const EvidenceMemoryParams& params() const { return p_; }

 private:
  EvidenceMemoryParams p_;
  double memory_s_;
};

}  // namespace odotune::filters
