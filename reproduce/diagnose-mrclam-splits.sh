#!/usr/bin/env bash
# MRCLAM robots 1–3 (commanded velocities against Vicon, first 900 s of each;
# ../shared/data/real/mrclam7/SOURCE.md), diagnosed across robots in every
# split: two fitted and the third held out (three ways), one fitted and the
# other two held out (three ways). Writes per split the summary (.txt), the
# JSON and the wall time; docs/diagnosis/README.md reads them.
#   bash reproduce/diagnose-mrclam-splits.sh [OUT_DIR]   (default out/mrclam-splits)
# Needs build/odotune (bash scripts/build.sh). About 30 minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
OUT=${1:-out/mrclam-splits}
BIN=${BIN:-build/odotune}
mkdir -p "$OUT/tracks"
for r in 1 2 3; do
  "$BIN" import mrclam "$REAL/mrclam7" --robot $r -o "$OUT/tracks/robot$r.csv" > /dev/null
done
T=$OUT/tracks
split() {  # name "fitted robots" "held-out robots"
  local name=$1 fit=() held=()
  for r in $2; do fit+=("$T/robot$r.csv"); done
  for r in $3; do held+=(--heldout "$T/robot$r.csv"); done
  echo "== $name (fitted: robots $2; held out: robots $3)" | tee "$OUT/$name.txt"
  local t0=$SECONDS
  "$BIN" diagnose "${fit[@]}" "${held[@]}" --to 900 --json "$OUT/$name.json" 2>&1 | tee -a "$OUT/$name.txt"
  echo "wall $((SECONDS - t0)) s" | tee -a "$OUT/$name.txt"
}
split fit-1-2-held-3 "1 2" "3"
split fit-1-3-held-2 "1 3" "2"
split fit-2-3-held-1 "2 3" "1"
split fit-1-held-2-3 "1" "2 3"
split fit-2-held-1-3 "2" "1 3"
split fit-3-held-1-2 "3" "1 2"
