#!/usr/bin/env bash
# The seven OptiOdom runs of the three recording days as odotune tracks
# (`odotune import optiodom`), named by their run, in DIR; shared by the
# scripts that hold out by day (diagnose-optiodom-days.sh, learned-real.sh).
#   bash reproduce/optiodom-days-tracks.sh DIR     (BIN and REAL as there)
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
BIN=${BIN:-build/odotune}
OO=$REAL/optiodom_diff
T=$1
mkdir -p "$T"
for run in square/231220200045/231220200045_run-01 square/231220200045/231220200045_run-02 \
           circular/231220200146/231220200146_run-01 circular/231220200146/231220200146_run-02 \
           free/020120212354/020120212354_run-01 \
           free/030120210001/030120210001_run-01 free/030120210001/030120210001_run-02; do
  "$BIN" import optiodom "$OO/$run.csv" -o "$T/$(basename "$run").csv" > /dev/null
done
