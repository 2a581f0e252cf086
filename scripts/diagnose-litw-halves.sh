#!/usr/bin/env bash
# Lost in the Woods (../shared/data/real/utias_lost_in_the_woods/SOURCE.md),
# its first half fitted and its second half held out, as two recordings of
# one robot: what the diagnosis of the first 10.5 minutes predicts about the
# next 10.5. The halves are the imported track's rows before and after the
# middle time (header kept, name suffixed).
#   bash scripts/diagnose-litw-halves.sh [OUT_DIR]   (default out/litw-halves)
# Needs build/odotune (bash scripts/build.sh). About a minute on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
OUT=${1:-out/litw-halves}
BIN=${BIN:-build/odotune}
mkdir -p "$OUT/tracks"
T=$OUT/tracks
"$BIN" import litw "$REAL/utias_lost_in_the_woods/derived/litw_series.csv" -o "$T/litw.csv" > /dev/null
bash scripts/split-track-halves.sh "$T/litw.csv" "$T/litw"
echo "== litw-halves (first half fitted, second half held out)" | tee "$OUT/litw-halves.txt"
t=$SECONDS
"$BIN" diagnose "$T/litw-first-half.csv" --heldout "$T/litw-second-half.csv" --json "$OUT/litw-halves.json" 2>&1 |
  tee -a "$OUT/litw-halves.txt"
echo "wall $((SECONDS - t)) s" | tee -a "$OUT/litw-halves.txt"
