#!/usr/bin/env bash
# Calibrate, then tune (docs/robot-localization.md): on the folds of
# reproduce/rl-ground-truth.sh (its tracks and fixes in OUT/tracks), three
# set-ups judged against ground truth on the held-out recordings:
#   tune alone          the fold's tuned files (rl-ground-truth.sh);
#   calibration alone   the odometry calibrated from the fitted recordings'
#                       fixes (their ground truth removed): `calibrate
#                       --method batch-pose` for wheels, `--method batch` for
#                       a twist or commands (scales, and a delay for commands),
#                       applied to the held-out recordings (`eval --calibration`)
#                       with the user's file;
#   calibrate, then tune the tune (same search and seeds) on the calibrated
#                       fitted recordings, judged with the calibration applied.
# Writes OUT/DATASET/FOLD/sSIGMA/calibrated/ for the DATASETS (default
# "optiodom litw mrclam"). Run by rl-ground-truth.sh.
#   bash reproduce/rl-calibrate-then-tune.sh [OUT_DIR]   (default out/rl-ground-truth)
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-out/rl-ground-truth}
BIN=${BIN:-build/odotune}
SEEDS=${SEEDS:-"1 2 3"}
SIGMAS=${SIGMAS:-"0.1 1"}
T=$OUT/tracks
DEC=(231220200045_run-01 231220200045_run-02 231220200146_run-01 231220200146_run-02)
JAN=(020120212354_run-01 030120210001_run-01 030120210001_run-02)

# fold DATASET FOLD SIGMA STRIDE METHOD FIT... -- HELD...
fold() {
  local dataset=$1 name=$2 sigma=$3 stride=$4 method=$5
  shift 5
  local fit=() fixes_only=() dir=$OUT/$dataset/$name/s$sigma/calibrated
  mkdir -p "$dir/starts"
  while [ "$1" != "--" ]; do
    fit+=(--track "$T/$1-s$sigma.csv")
    python3 reproduce/strip_ground_truth.py "$T/$1-s$sigma.csv" "$dir/$1-fixes-only.csv"
    fixes_only+=(--track "$dir/$1-fixes-only.csv")
    shift
  done
  shift
  local t0=$SECONDS first=${SEEDS%% *} n
  n=$(wc -w <<< "$SEEDS")
  if ! grep -q '^wall' "$dir/tune.txt" 2> /dev/null; then  # resumes: a fold done is kept
    # A fit `calibrate` refuses (not a geometry the robot can have) leaves the
    # fold without calibrated set-ups; the tables list the refusal.
    if ! "$BIN" calibrate "${fixes_only[@]}" --method "$method" --config-out "$dir/calibration.yaml" \
      > "$dir/calibration.txt" 2> "$dir/calibration-refused.txt"; then
      echo "$dataset $name sigma $sigma: $(cat "$dir/calibration-refused.txt")"
      return 0
    fi
    rm -f "$dir/calibration-refused.txt"
    "$BIN" tune --rl-params "$OUT/$dataset/user.yaml" "${fit[@]}" --calibration "$dir/calibration.yaml" \
      --no-input-covariances --outage-every "$stride" --refine 1 --particles 8 --iterations 6 --seed "$first" \
      --starts "$n" --threads 2 --starts-out "$dir/starts" --config-out "$dir/tuned.yaml" > "$dir/tune.txt"
    echo "wall $((SECONDS - t0)) s" >> "$dir/tune.txt"
  fi
  for r in "$@"; do
    [ -f "$dir/user-$r.json" ] ||
      "$BIN" eval --rl-params "$OUT/$dataset/user.yaml" --track "$T/$r-s$sigma.csv" \
        --calibration "$dir/calibration.yaml" --outage-every "$stride" --json "$dir/user-$r.json" > "$dir/user-$r.txt"
    for seed in $SEEDS; do
      [ -f "$dir/seed$seed-$r.json" ] ||
        "$BIN" eval --rl-params "$dir/starts/ekf-seed$seed.yaml" --track "$T/$r-s$sigma.csv" \
          --calibration "$dir/calibration.yaml" --outage-every "$stride" --json "$dir/seed$seed-$r.json" > /dev/null
    done
  done
  echo "$dataset $name sigma $sigma, calibrated: $((SECONDS - t0)) s"
}
for d in ${DATASETS:-optiodom litw mrclam}; do
  for s in $SIGMAS; do
    case $d in
      optiodom)
        fold optiodom tune-dec23 "$s" 10 batch-pose "${DEC[@]}" -- "${JAN[@]}"
        fold optiodom tune-jan "$s" 10 batch-pose "${JAN[@]}" -- "${DEC[@]}" ;;
      mrclam)
        fold mrclam tune-12 "$s" 30 batch robot1 robot2 -- robot3
        fold mrclam tune-13 "$s" 30 batch robot1 robot3 -- robot2
        fold mrclam tune-23 "$s" 30 batch robot2 robot3 -- robot1 ;;
      litw) fold litw tune-first "$s" 30 batch litw-first-half -- litw-second-half ;;
      *) echo "rl-calibrate-then-tune.sh: DATASETS: unknown dataset '$d' (expected optiodom, mrclam or litw)" >&2; exit 2 ;;
    esac
  done
done
