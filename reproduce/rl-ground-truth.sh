#!/usr/bin/env bash
# robot_localization's EKF tuned without ground truth and judged against it,
# on held-out recordings (docs/robot-localization.md):
#   OptiOdom (wheel encoders): tuned on the four 23 Dec runs, judged on the
#     three 2-3 Jan runs, and the reverse;
#   MRCLAM robots 1-3 (commands): tuned on two, judged on the third, all three ways;
#   Lost in the Woods (a measured twist): tuned on the first half, judged on the second.
# Each with 1 Hz fixes from `odotune fixes` (seed FIX_SEED, default 1) at sigma 0.1 m (an indoor
# positioning system) and 1 m (a GPS). The user's file, as a team writes it
# (two_d_mode, the odometry's velocities, the fixes as x, y, robot_localization's
# default noise; none of the three robots has a gyro): OUT/DATASET/user.yaml.
# The tune (`tune --rl-params ... --track ...`, all fitted recordings together,
# their ground truth unused): a grid, then PSO within 1 decade from seeds
# SEEDS (default 1 2 3), each seed's file in OUT/DATASET/FOLD/sSIGMA/starts/;
# the file of lowest tuning fitness is tuned.yaml there, and the first fold's
# at the first sigma (0.1 m) is also OUT/DATASET/tuned.yaml. Every held-out recording is
# scored (`eval`) with the user's file and each seed's: against ground truth
# (the whole run with the fixes fused; simulated fix outages) and against the
# fixes (held-out folds, outages), as a user without ground truth sees them.
# The tables: OUT/tables.md.
#   bash reproduce/rl-ground-truth.sh [OUT_DIR]        (default out/rl-ground-truth)
# Needs build/odotune. BIN, REAL and SEEDS as above; SIGMAS (default 0.1 1);
# DATASETS (default "optiodom litw mrclam", the longest tunes last; a rerun
# with more resumes). The tables cover the folds done so far. TUNE_EXTRA:
# more tune flags (e.g. --subtract-fix-variance); FOLDS_ONLY=1 skips the
# calibrate-then-tune and physics stages (other fix seeds and fitnesses:
# docs/robot-localization.md, "Other fix seeds").
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
OUT=${1:-out/rl-ground-truth}
BIN=${BIN:-build/odotune}
SEEDS=${SEEDS:-"1 2 3"}
SIGMAS=${SIGMAS:-"0.1 1"}
DATASETS=${DATASETS:-"optiodom litw mrclam"}
FIX_SEED=${FIX_SEED:-1}
TUNE_EXTRA=${TUNE_EXTRA:-}
FOLDS_ONLY=${FOLDS_ONLY:-0}
for d in $DATASETS; do
  case $d in optiodom | mrclam | litw) ;;
    *) echo "rl-ground-truth.sh: DATASETS: unknown dataset '$d' (expected optiodom, mrclam or litw)" >&2; exit 2 ;;
  esac
done
T=$OUT/tracks
mkdir -p "$T"
start=$SECONDS

DEC=(231220200045_run-01 231220200045_run-02 231220200146_run-01 231220200146_run-02)
JAN=(020120212354_run-01 030120210001_run-01 030120210001_run-02)

# ---------------------------------------------------------------- tracks and fixes
# (made once: a rerun into the same OUT resumes where it stopped)
if [ ! -f "$T/done" ]; then
  REAL="$REAL" BIN="$BIN" bash reproduce/real-tracks.sh "$T"
  for name in "${DEC[@]}" "${JAN[@]}" robot1 robot2 robot3 litw-first-half litw-second-half; do
    for s in $SIGMAS; do
      "$BIN" fixes "$T/$name.csv" -o "$T/$name-s$s.csv" --rate-hz 1 --sigma-m "$s" --seed "$FIX_SEED" > /dev/null
    done
  done
  touch "$T/done"
fi

# ---------------------------------------------------------------- the user's file
# user_file DATASET ODOMETRY: what a team writes for its robot.
user_file() {
  mkdir -p "$OUT/$1"
  cat > "$OUT/$1/user.yaml" << YAML
# robot_localization's ekf_node as a team sets it up for this robot ($2) with
# an absolute position source: two_d_mode, the odometry's velocities, the
# fixes as x, y; robot_localization's default noise (process_noise_covariance
# and initial_estimate_covariance not set). No gyro: the robot has none.
# initial_state is set by the replay to the first fix of each recording, with
# the heading that aligns the odometry with the first fixes.
ekf_filter_node:
  ros__parameters:
    frequency: 30.0
    two_d_mode: true
    odom_frame: odom
    base_link_frame: base_link
    world_frame: odom
    # odom0: the drive controller's odometry, vx, vy (0 for a differential
    # drive) and vyaw. Its twist covariance is what ros2_control's
    # diff_drive_controller publishes with Clearpath's setting,
    # twist_covariance_diagonal [0.001, 0.001, 0.001, 1e6, 1e6, 0.03].
    odom0: odom
    odom0_config: [false, false, false,
                   false, false, false,
                   true,  true,  false,
                   false, false, true,
                   false, false, false]
    # odom1: the position fixes (an indoor positioning system, or a GPS
    # through navsat_transform_node), x and y with their own variances.
    odom1: odometry/fixes
    odom1_config: [true,  true,  false,
                   false, false, false,
                   false, false, false,
                   false, false, false,
                   false, false, false]
YAML
}
user_file optiodom "wheel encoders through the nominal geometry"
user_file mrclam "the velocity commands, its only odometry"
user_file litw "the measured body twist"

# ---------------------------------------------------------------- folds
# fold DATASET FOLD SIGMA STRIDE FIT... -- HELD...: the tune on FIT, the user's
# and every seed's file scored on each HELD recording.
fold() {
  local dataset=$1 name=$2 sigma=$3 stride=$4
  shift 4
  local fit=() dir=$OUT/$dataset/$name/s$sigma
  while [ "$1" != "--" ]; do fit+=(--track "$T/$1-s$sigma.csv"); shift; done
  shift
  mkdir -p "$dir/starts"
  local t0=$SECONDS first=${SEEDS%% *} n
  n=$(wc -w <<< "$SEEDS")
  # A fold already done (its tune's wall time written last) is kept: the script resumes.
  if ! grep -q '^wall' "$dir/tune.txt" 2> /dev/null; then
    # shellcheck disable=SC2086 # TUNE_EXTRA: flags, split into words on purpose
    "$BIN" tune --rl-params "$OUT/$dataset/user.yaml" "${fit[@]}" --no-input-covariances --outage-every "$stride" \
      $TUNE_EXTRA --refine 1 --particles 8 --iterations 6 --seed "$first" --starts "$n" --threads 2 \
      --starts-out "$dir/starts" --config-out "$dir/tuned.yaml" --json "$dir/tune.json" > "$dir/tune.txt"
    echo "wall $((SECONDS - t0)) s" >> "$dir/tune.txt"
  fi
  for r in "$@"; do
    [ -f "$dir/user-$r.json" ] ||
      "$BIN" eval --rl-params "$OUT/$dataset/user.yaml" --track "$T/$r-s$sigma.csv" --outage-every "$stride" \
        --json "$dir/user-$r.json" > "$dir/user-$r.txt"
    for seed in $SEEDS; do
      [ -f "$dir/seed$seed-$r.json" ] ||
        "$BIN" eval --rl-params "$dir/starts/ekf-seed$seed.yaml" --track "$T/$r-s$sigma.csv" \
          --outage-every "$stride" --json "$dir/seed$seed-$r.json" > "$dir/seed$seed-$r.txt"
    done
  done
  echo "$dataset $name sigma $sigma: $((SECONDS - t0)) s"
}
# folds DATASET SIGMA: the dataset's folds (list above).
folds() {
  case $1 in
    optiodom)
      fold optiodom tune-dec23 "$2" 10 "${DEC[@]}" -- "${JAN[@]}"
      fold optiodom tune-jan "$2" 10 "${JAN[@]}" -- "${DEC[@]}" ;;
    mrclam)
      fold mrclam tune-12 "$2" 30 robot1 robot2 -- robot3
      fold mrclam tune-13 "$2" 30 robot1 robot3 -- robot2
      fold mrclam tune-23 "$2" 30 robot2 robot3 -- robot1 ;;
    litw) fold litw tune-first "$2" 30 litw-first-half -- litw-second-half ;;
  esac
}
declare -A FIRST=([optiodom]=tune-dec23 [mrclam]=tune-12 [litw]=tune-first)
for d in $DATASETS; do
  for s in $SIGMAS; do folds "$d" "$s"; done
  cp "$OUT/$d/${FIRST[$d]}/s${SIGMAS%% *}/tuned.yaml" "$OUT/$d/tuned.yaml"
done

if [ "$FOLDS_ONLY" != 1 ]; then
  BIN="$BIN" SEEDS="$SEEDS" SIGMAS="$SIGMAS" DATASETS="$DATASETS" bash reproduce/rl-calibrate-then-tune.sh "$OUT"
  BIN="$BIN" bash reproduce/rl-physics-sim.sh "$OUT"
fi
python3 reproduce/rl-ground-truth-tables.py "$OUT" "$SEEDS" "$SIGMAS" "$FIX_SEED" "$TUNE_EXTRA" | tee "$OUT/tables.md"
echo "wall $((SECONDS - start)) s"
