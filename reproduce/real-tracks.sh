#!/usr/bin/env bash
# The real recordings with ground truth as tracks, into DIR: OptiOdom's seven
# runs of its three days (optiodom-days-tracks.sh), MRCLAM robots 1-3
# (robot1.csv … robot3.csv) and Lost in the Woods (litw.csv, and its halves
# litw-first-half.csv, litw-second-half.csv). Shared by learned-real.sh and
# rl-ground-truth.sh.
#   bash reproduce/real-tracks.sh DIR        (BIN, REAL as those scripts)
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
BIN=${BIN:-build/odotune}
T=$1
mkdir -p "$T"
REAL="$REAL" BIN="$BIN" bash reproduce/optiodom-days-tracks.sh "$T"
for r in 1 2 3; do "$BIN" import mrclam "$REAL/mrclam7" --robot $r -o "$T/robot$r.csv" > /dev/null; done
"$BIN" import litw "$REAL/utias_lost_in_the_woods/derived/litw_series.csv" -o "$T/litw.csv" > /dev/null
bash reproduce/track-halves.sh "$T/litw.csv" "$T" litw > /dev/null
