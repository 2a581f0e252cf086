#!/usr/bin/env bash
# Online and batch odometry calibration on the real OptiOdom recordings of
# ../shared/data/real/optiodom_diff (SOURCE.md there: Sousa et al., JINT 2022,
# MIT licence), and the held-out check that docs/calibration/real-data.md
# reports: calibrate on three runs, replay four other runs with the result.
#   bash scripts/calibrate-real.sh [OUT_DIR]      (default out/calibration-real)
# Needs build/odotune (bash scripts/build.sh).
#
# The robot has no lidar: its external body velocities are derived from the
# OptiTrack ground truth at 10 Hz (--ext-from-gt 10), a stand-in for scan
# matching, with σ 0.005 m/s and 0.005 rad/s (OptiTrack positions are good to about
# a millimetre; 1 mm over 0.1 s is 0.01 m/s per difference, halved by the 20 Hz
# resampling).
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
OUT=${1:-out/calibration-real}
BIN=${BIN:-build/odotune}
OO=$REAL/optiodom_diff
mkdir -p "$OUT/tracks"

import() {  # relative run path without .csv → prints the imported track path
  local name
  name=optiodom-$(basename "$1" | tr '_' '-')
  "$BIN" import optiodom "$OO/$1.csv" -o "$OUT/tracks/$name.csv" > /dev/null
  echo "$OUT/tracks/$name.csv"
}

CAL=()
for r in circular/231220200146/231220200146_run-01 square/231220200045/231220200045_run-01 \
         free/030120210001/030120210001_run-01; do
  CAL+=("$(import "$r")")
done
HELD=()
for r in circular/231220200146/231220200146_run-02 square/231220200045/231220200045_run-02 \
         free/020120212354/020120212354_run-01 free/030120210001/030120210001_run-02; do
  HELD+=("$(import "$r")")
done

cal_args=()
for t in "${CAL[@]}"; do cal_args+=(--track "$t"); done
held_args=()
for t in "${HELD[@]}"; do held_args+=(--track "$t"); done

for method in batch adaptive-pf pf dkf; do
  echo "== calibrate $method on ${#CAL[@]} runs" | tee "$OUT/$method.txt"
  t0=$SECONDS
  "$BIN" calibrate "${cal_args[@]}" --method "$method" --ext-from-gt 10 --ext-sigma-v 0.005 --ext-sigma-w 0.005 --seed 1 \
    --json "$OUT/$method.json" --csv "$OUT/$method.csv" --figure "$OUT/$method" \
    --config-out "$OUT/$method.yaml" 2>&1 | tee -a "$OUT/$method.txt"
  echo "wall $((SECONDS - t0)) s" | tee -a "$OUT/$method.txt"
  echo "== held-out replay with the $method calibration" | tee "$OUT/$method-heldout.txt"
  "$BIN" calibrate "${held_args[@]}" --apply "$OUT/$method.yaml" \
    --json "$OUT/$method-heldout.json" 2>&1 | tee -a "$OUT/$method-heldout.txt"
done
