#!/usr/bin/env bash
# Diagnoses the real recordings of ../shared/data/real (see each SOURCE.md)
# and writes what docs/diagnosis/README.md shows: per recording the summary
# (stdout), the JSON (diagnosis-output.md) and the report folder.
#   bash reproduce/diagnose-real.sh [OUT_DIR]      (default out/diagnosis-real)
# Needs build/odotune (bash scripts/build.sh). Single recordings: MRCLAM is cut
# to its first 300 s (--to 300; the held-out check uses the last 30 % of
# that); Lost in the Woods is diagnosed whole (21 min). Several recordings of
# one robot (issue 15): OptiOdom fitted on two runs and proven on three others,
# MRCLAM robot 1 fitted and robots 2 and 3 held out (first 900 s of each).
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
OUT=${1:-out/diagnosis-real}
BIN=${BIN:-build/odotune}
mkdir -p "$OUT/tracks"

run() {  # name track [more tracks and diagnose options...]
  local name=$1 track=$2
  shift 2
  echo "== $name" | tee "$OUT/$name.txt"
  local t0=$SECONDS
  "$BIN" diagnose "$track" --json "$OUT/$name.json" --report "$OUT/$name-report" "$@" 2>&1 |
    tee -a "$OUT/$name.txt"
  echo "wall $((SECONDS - t0)) s" | tee -a "$OUT/$name.txt"
}

OO=$REAL/optiodom_diff
for run_csv in free/020120212354/020120212354_run-01 free/030120210001/030120210001_run-01 \
               square/231220200045/231220200045_run-01 circular/231220200146/231220200146_run-01; do
  name=optiodom-$(basename "$run_csv" | tr '_' '-')
  "$BIN" import optiodom "$OO/$run_csv.csv" -o "$OUT/tracks/$name.csv" > /dev/null
  run "$name" "$OUT/tracks/$name.csv"
done

for r in 1 2 3; do
  "$BIN" import mrclam "$REAL/mrclam7" --robot $r -o "$OUT/tracks/mrclam-robot$r.csv" > /dev/null
done
run mrclam-robot1 "$OUT/tracks/mrclam-robot1.csv" --to 300
run mrclam-robot1-heldout-2-3 "$OUT/tracks/mrclam-robot1.csv" --heldout "$OUT/tracks/mrclam-robot2.csv" \
  "$OUT/tracks/mrclam-robot3.csv" --to 900

for run_csv in free/030120210001/030120210001_run-02 circular/231220200146/231220200146_run-02 \
               square/231220200045/231220200045_run-02; do
  "$BIN" import optiodom "$OO/$run_csv.csv" -o "$OUT/tracks/optiodom-$(basename "$run_csv" | tr '_' '-').csv" > /dev/null
done
T=$OUT/tracks
run optiodom-pooled "$T/optiodom-030120210001-run-01.csv" "$T/optiodom-231220200146-run-01.csv" \
  --heldout "$T/optiodom-030120210001-run-02.csv" "$T/optiodom-231220200146-run-02.csv" \
  "$T/optiodom-020120212354-run-01.csv"

"$BIN" import litw "$REAL/utias_lost_in_the_woods/derived/litw_series.csv" \
  -o "$OUT/tracks/litw.csv" > /dev/null
run litw "$OUT/tracks/litw.csv"
