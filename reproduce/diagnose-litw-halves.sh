#!/usr/bin/env bash
# Lost in the Woods (../shared/data/real/utias_lost_in_the_woods/SOURCE.md),
# its first half fitted and its second half held out, as two recordings of
# one robot: what the diagnosis of the first 10.5 minutes predicts about the
# next 10.5. The halves are the imported track's rows before and after the
# middle time (header kept, name suffixed).
#   bash reproduce/diagnose-litw-halves.sh [OUT_DIR]   (default out/litw-halves)
# Needs build/odotune (bash scripts/build.sh). About a minute on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
OUT=${1:-out/litw-halves}
BIN=${BIN:-build/odotune}
mkdir -p "$OUT/tracks"
T=$OUT/tracks
"$BIN" import litw "$REAL/utias_lost_in_the_woods/derived/litw_series.csv" -o "$T/litw.csv" > /dev/null
BIN=$BIN bash reproduce/diagnose-track-halves.sh "$T/litw.csv" "$OUT" litw
