#!/usr/bin/env bash
# OptiOdom (../shared/data/real/optiodom_diff/SOURCE.md: a differential-drive
# robot's wheel encoders against OptiTrack), diagnosed across recording days:
# the runs of one day fitted (cross-validated by leaving one run out), the
# runs of the other days held out. Days by the recording's id (DDMMYYYYhhmm):
# 23 Dec 2020 (square and circular, 2 runs each), 2 Jan 2021 23:54 (free,
# 1 run), 3 Jan 2021 00:01 (free, 2 runs; minutes after the 2 Jan one).
#   bash reproduce/diagnose-optiodom-days.sh [OUT_DIR]   (default out/optiodom-days)
# Needs build/odotune (bash scripts/build.sh). About a minute on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
OUT=${1:-out/optiodom-days}
BIN=${BIN:-build/odotune}
mkdir -p "$OUT/tracks"
T=$OUT/tracks
REAL="$REAL" BIN="$BIN" bash reproduce/optiodom-days-tracks.sh "$T"
DEC23=("$T/231220200045_run-01.csv" "$T/231220200045_run-02.csv" "$T/231220200146_run-01.csv" "$T/231220200146_run-02.csv")
JAN02=("$T/020120212354_run-01.csv")
JAN03=("$T/030120210001_run-01.csv" "$T/030120210001_run-02.csv")
day() {  # name, then the fitted runs, "--", the held-out runs
  local name=$1
  shift
  local fit=() out=()
  while [ "$1" != "--" ]; do fit+=("$1"); shift; done
  shift
  for f in "$@"; do out+=(--heldout "$f"); done
  echo "== $name" | tee "$OUT/$name.txt"
  local t0=$SECONDS
  "$BIN" diagnose "${fit[@]}" "${out[@]}" --json "$OUT/$name.json" 2>&1 | tee -a "$OUT/$name.txt"
  echo "wall $((SECONDS - t0)) s" | tee -a "$OUT/$name.txt"
}
day fit-dec23 "${DEC23[@]}" -- "${JAN02[@]}" "${JAN03[@]}"
day fit-jan02 "${JAN02[@]}" -- "${DEC23[@]}" "${JAN03[@]}"
day fit-jan03 "${JAN03[@]}" -- "${DEC23[@]}" "${JAN02[@]}"
