// The consumer's own filters/ekf.h: a project with a folder named like one of
// odotune's modules. odotune's headers are included as <odotune/filters/ekf.h>,
// so this one and odotune's never shadow each other.
#pragma once

namespace consumer {

// The consumer's own filter: an exponential moving average with gain k.
inline double smooth(double previous, double sample, double k) { return previous + k * (sample - previous); }

}  // namespace consumer
