#!/usr/bin/env bash
# One drive as two recordings: cuts an odotune track at the middle of its data
# rows' time span (OUT/tracks/NAME-first-half.csv, NAME-second-half.csv;
# metadata kept, "-first-half"/"-second-half" appended to the name) and runs
# `odotune diagnose FIRST --heldout SECOND`, writing OUT/NAME-halves.txt (the
# summary and the wall time) and OUT/NAME-halves.json.
#   bash reproduce/diagnose-track-halves.sh TRACK.csv OUT NAME   (BIN: the odotune binary)
set -euo pipefail
in=$1 out=$2 name=$3
BIN=${BIN:-build/odotune}
T=$out/tracks
mkdir -p "$T"
bash "$(dirname "$0")/track-halves.sh" "$in" "$T" "$name" > /dev/null
echo "== $name-halves (first half fitted, second half held out)" | tee "$out/$name-halves.txt"
t=$SECONDS
"$BIN" diagnose "$T/$name-first-half.csv" --heldout "$T/$name-second-half.csv" --json "$out/$name-halves.json" 2>&1 |
  tee -a "$out/$name-halves.txt"
echo "wall $((SECONDS - t)) s" | tee -a "$out/$name-halves.txt"
