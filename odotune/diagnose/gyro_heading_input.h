// The input for gyro-heading dead reckoning (docs/diagnosis-design.md, gyro
// findings): the odometry replaced by body velocities, the speed from the
// nominal wheel travel (or the input's own v for body-velocity odometry),
// the yaw rate from the gyro corrected by (bias, scale) (corrected_gyro_rate
// of effect_model.h; the gyro held constant outside its span). Replaying it
// with the nominal model is dead reckoning with the wheels' travel and the
// gyro's heading: how diagnosis.cpp proves a gyro finding, and how the
// random benchmark (odotune/studies/diagnosis_truth.h) judges a true gyro effect.
#pragma once

#include <odotune/diagnose/diag_input.h>

namespace odotune::diagnose {

// Commands are dropped (cmd_* empty). bias_radps [rad/s]; scale 1 = none.
DiagInput gyro_heading_input(const DiagInput& in, double bias_radps, double scale);

}  // namespace odotune::diagnose
