#!/usr/bin/env bash
# Learned odometry on a real robot, held out by recording (docs/learned/real.md):
# OptiOdom (../shared/data/real/optiodom_diff, SOURCE.md there: a differential
# robot with motion capture), trained on the 23 Dec runs and judged on the 2-3 Jan
# runs, and the reverse. For each fold: the paper's nets (--target velocity) and
# correction nets (--target correction, validated on the last training recording
# held out whole, --validation recordings; they fall back to the kinematic
# odometry when they do not beat it there), seed 1; the
# correction nets' verdict again with seeds 2 and 3. Each judged against the
# nominal kinematic odometry on every held-out run (learn eval).
#   bash reproduce/learned-real.sh [OUT_DIR]        (default out/learned-real)
# Needs build/odotune. BIN and REAL as in the other scripts. MRCLAM and Lost in the
# Woods have no wheel increments (commands, resp. a measured twist) and are not
# yet taken by `learn train`.
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
OUT=${1:-out/learned-real}
BIN=${BIN:-build/odotune}
T=$OUT/tracks
mkdir -p "$T"
REAL="$REAL" BIN="$BIN" bash reproduce/optiodom-days-tracks.sh "$T"
DEC=(231220200045_run-01 231220200045_run-02 231220200146_run-01 231220200146_run-02)
JAN=(020120212354_run-01 030120210001_run-01 030120210001_run-02)

fold() {  # name, target, seed, the training runs, "--", the held-out runs
  local name=$1 target=$2 seed=$3
  shift 3
  local train=()
  while [ "$1" != "--" ]; do train+=(--track "$T/$1.csv"); shift; done
  shift
  local dir=$OUT/$name/$target-seed$seed
  mkdir -p "$dir"
  local validation=chronological
  [ "$target" = correction ] && validation=recordings
  "$BIN" learn train "${train[@]}" --iterations 50 --seed "$seed" --target "$target" --validation $validation \
    --threads 2 --model-out "$dir/model.json" > "$dir/train.txt"
  for r in "$@"; do
    "$BIN" learn eval --track "$T/$r.csv" --model "$dir/model.json" --json "$dir/eval-$r.json" > "$dir/eval-$r.txt"
  done
}
for target in velocity correction; do
  fold train-dec23 "$target" 1 "${DEC[@]}" -- "${JAN[@]}"
  fold train-jan "$target" 1 "${JAN[@]}" -- "${DEC[@]}"
done
for seed in 2 3; do
  fold train-dec23 correction "$seed" "${DEC[@]}" -- "${JAN[@]}"
  fold train-jan correction "$seed" "${JAN[@]}" -- "${DEC[@]}"
done

python3 - "$OUT" <<'PY' | tee "$OUT/table.md"
import glob, json, os, sys
out = sys.argv[1]
print("| fold | held-out run | odometry | V MAE [m/s] | W MAE [rad/s] | XY RMSE [m] | θ RMSE [rad] | XY ÷ kinematic |")
print("|---|---|---|---:|---:|---:|---:|---:|")
for fold in ("train-dec23", "train-jan"):
    for path in sorted(glob.glob(f"{out}/{fold}/velocity-seed1/eval-*.json")):
        run = os.path.basename(path)[5:-5]
        rows = [("kinematic", json.load(open(path))["kinematic"])]
        for target in ("velocity", "correction"):
            rows.append((f"learned, {target}", json.load(open(f"{out}/{fold}/{target}-seed1/eval-{run}.json"))["learned"]))
        k = rows[0][1]["pos_rmse_m"]
        for name, e in rows:
            print(f"| {fold} | {run} | {name} | {e['v_mae']:.4f} | {e['w_mae']:.4f} | {e['pos_rmse_m']:.3f} | "
                  f"{e['theta_rmse_rad']:.3f} | {e['pos_rmse_m'] / k:.2f} |")
print()
print("Correction nets' verdict in training (free-running MAE on the held-out training recording against the kinematic odometry's):")
print()
for fold in ("train-dec23", "train-jan"):
    for seed in (1, 2, 3):
        d = f"{out}/{fold}/correction-seed{seed}"
        line = [l for l in open(f"{d}/train.txt") if "free-running" in l]
        ratios = []
        for path in sorted(glob.glob(f"{d}/eval-*.json")):
            e = json.load(open(path))
            ratios.append(f"{e['learned']['pos_rmse_m'] / e['kinematic']['pos_rmse_m']:.2f}")
        print(f"- {fold}, seed {seed}:{line[0].split(':', 1)[1].rstrip()}; held out, XY RMSE ÷ kinematic's: "
              + ", ".join(ratios))
PY
