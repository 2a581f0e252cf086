#!/usr/bin/env bash
# Learned odometry on real robots, held out by recording (docs/learned/real.md).
#   OptiOdom (wheel encoders, ../shared/data/real/optiodom_diff): trained on the
#     four 23 Dec runs, judged on the three 2-3 Jan runs, and the reverse;
#   MRCLAM robots 1-3 (commands, ../shared/data/real/mrclam7): trained on two,
#     judged on the third, all three ways;
#   Lost in the Woods (a measured twist, ../shared/data/real/utias_lost_in_the_woods):
#     trained on the first half, judged on the second, and the reverse.
# For each fold and seed (SEEDS, default 1 2 3): correction nets chosen by
# cross-validation inside the training recordings (`learn train`, defaults),
# with a slip detector trained on the same recordings; the kinematics
# calibrated on the same recordings (`calibrate --method batch`); each
# held-out recording scored (`learn eval`) for the learned, nominal and
# calibrated kinematics, and fused with 1 Hz fixes (`odotune fixes`, σ 0.1 m,
# seed 1). OptiOdom also with the paper's velocity nets (seed 1). One
# held-out recording per dataset is retrained on its first half (reference:
# velocities from its ground truth at 10 Hz) and judged on its second half.
# The tables: OUT/tables.md (docs/learned/real.md reads them).
#   bash reproduce/learned-real.sh [OUT_DIR]        (default out/learned-real)
# Needs build/odotune. BIN, REAL and SEEDS as above. About an hour on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
OUT=${1:-out/learned-real}
BIN=${BIN:-build/odotune}
SEEDS=${SEEDS:-"1 2 3"}
T=$OUT/tracks
mkdir -p "$T"
start=$SECONDS

# ---------------------------------------------------------------- tracks
REAL="$REAL" BIN="$BIN" bash reproduce/real-tracks.sh "$T"
DEC=(231220200045_run-01 231220200045_run-02 231220200146_run-01 231220200146_run-02)
JAN=(020120212354_run-01 030120210001_run-01 030120210001_run-02)
for name in "${DEC[@]}" "${JAN[@]}" robot1 robot2 robot3 litw-first-half litw-second-half; do
  "$BIN" fixes "$T/$name.csv" -o "$T/$name-fixes.csv" --rate-hz 1 --sigma-m 0.1 --seed 1 > /dev/null
done

# ---------------------------------------------------------------- folds
# fold DATASET FOLD SEED TRAIN... -- HELD...: correction nets, their slip
# detector, the calibration (once per fold) and every held-out recording.
fold() {
  local dataset=$1 name=$2 seed=$3
  shift 3
  local train=() slips=()
  while [ "$1" != "--" ]; do train+=(--track "$T/$1.csv"); slips+=(--slip-track "$T/$1.csv"); shift; done
  shift
  local base=$OUT/$dataset/$name dir=$OUT/$dataset/$name/seed$seed
  mkdir -p "$dir"
  [ -f "$base/calibration.yaml" ] ||
    "$BIN" calibrate "${train[@]}" --method batch --config-out "$base/calibration.yaml" > "$base/calibration.txt"
  local t0=$SECONDS
  "$BIN" learn train "${train[@]}" "${slips[@]}" --seed "$seed" --iterations 60 --threads 2 \
    --model-out "$dir/model.json" > "$dir/train.txt"
  echo "wall $((SECONDS - t0)) s" >> "$dir/train.txt"
  for r in "$@"; do
    "$BIN" learn eval --track "$T/$r-fixes.csv" --model "$dir/model.json" --calibration "$base/calibration.yaml" \
      --fix-sigma-m 0.1 --json "$dir/eval-$r.json" --csv "$dir/eval-$r.csv" > "$dir/eval-$r.txt"
  done
  echo "$dataset $name seed $seed: $((SECONDS - t0)) s"
}
for seed in $SEEDS; do
  fold optiodom train-dec23 "$seed" "${DEC[@]}" -- "${JAN[@]}"
  fold optiodom train-jan "$seed" "${JAN[@]}" -- "${DEC[@]}"
  fold mrclam train-12 "$seed" robot1 robot2 -- robot3
  fold mrclam train-13 "$seed" robot1 robot3 -- robot2
  fold mrclam train-23 "$seed" robot2 robot3 -- robot1
  fold litw train-first "$seed" litw-first-half -- litw-second-half
  fold litw train-second "$seed" litw-second-half -- litw-first-half
done

# The paper's velocity nets on OptiOdom (wheel increments only), seed 1.
for f in "train-dec23:${DEC[*]}:${JAN[*]}" "train-jan:${JAN[*]}:${DEC[*]}"; do
  IFS=: read -r name train held <<< "$f"
  dir=$OUT/optiodom/$name/velocity
  mkdir -p "$dir"
  args=()
  for r in $train; do args+=(--track "$T/$r.csv"); done
  "$BIN" learn train "${args[@]}" --target velocity --iterations 50 --seed 1 --threads 2 \
    --model-out "$dir/model.json" > "$dir/train.txt"
  for r in $held; do "$BIN" learn eval --track "$T/$r.csv" --model "$dir/model.json" --json "$dir/eval-$r.json" > /dev/null; done
done

# ---------------------------------------------------------------- retraining
# retrain DATASET FOLD HELD: seed 1's model retrained on the held-out
# recording's first half, both models judged on its second half.
retrain() {
  local dataset=$1 name=$2 held=$3
  local dir=$OUT/$dataset/$name/seed1 track=$T/$3.csv
  local mid
  mid=$(awk -F, '!/^#/ && $1 ~ /^[0-9.]+$/ {if (!n++) a = $1; b = $1} END {print (a + b) / 2}' "$track")
  "$BIN" learn retrain --track "$track" --model "$dir/model.json" --static-covariance --ext-from-gt 10 \
    --until "$mid" --model-out "$dir/retrained-$held.json" --json "$dir/retrain-$held.json" > "$dir/retrain-$held.txt"
  for m in model "retrained-$held"; do
    "$BIN" learn eval --track "$track" --model "$dir/$m.json" --from "$mid" --json "$dir/second-half-$m-$held.json" > /dev/null
  done
}
retrain optiodom train-dec23 020120212354_run-01
retrain mrclam train-12 robot3
retrain litw train-first litw-second-half

python3 reproduce/learned-real-tables.py "$OUT" "$SEEDS" | tee "$OUT/tables.md"
echo "wall $((SECONDS - start)) s"
