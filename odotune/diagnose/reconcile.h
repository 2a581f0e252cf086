// The sensor checks reconciled with the findings: every
// check that flags a departure (sensor_checks.h: a speed or yaw-rate ratio
// off 1, a gyro bias or scale, a lag between odometry and reference or
// between commands and motion) either is carried by a finding of an effect
// that produces it, or the diagnosis says why no such finding was made (the
// selection's reason for the effect that would carry it, or its materiality).
// A flagged ratio is evidence, not a finding: the ratio is a regression of
// binned speeds, sensitive to what the reference's bins average over, while a
// finding must predict held-out windows.
#pragma once

#include <string>
#include <vector>

#include <odotune/diagnose/diagnosis.h>

namespace odotune::diagnose {

// One line per flagged check, e.g. "speed ratio 0.930 (z = -35.2): carried by
// radius_error" or "... is not a finding: radius_error was tried and rejected
// (best candidate rejected: immaterial: ...)". Empty when nothing is flagged.
// Reads d.sensors, d.findings, d.immaterial and d.selection.records.
std::vector<std::string> reconcile_sensor_checks(const Diagnosis& d);

}  // namespace odotune::diagnose
