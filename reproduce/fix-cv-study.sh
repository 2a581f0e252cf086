#!/usr/bin/env bash
# Does tuning without ground truth work? On simulated tracks, which have
# ground truth, each EKF noise model is tuned twice with the same solver and
# budget: with fitness mode 1 (RMSE against ground truth) and with the
# fix cross-validation modes 8 and 9 (held-out fixes only, no ground truth).
# The figure is the ratio of the ground-truth RMSE the no-ground-truth tune
# reaches to the ground-truth tune's: issue 17 asks for ≤ 1.10.
#
#   bash reproduce/fix-cv-study.sh [OUT_DIR] [SEEDS]   (default out/fix-cv-study, "201 202 203")
#
# Robots and drives: the study's small robot on its five reference drives
# (scenarios/track1-5.yaml: 1 Hz fixes, σ 60 mm), the wheelchair
# (scenarios/wheelchair.yaml, fixes added at 1 Hz, σ 0.10 m) and the slow
# robot (scenarios/slow_robot.yaml, fixes at 2 Hz, σ 0.02 m). Noise seeds 201-203
# are the documented, held-out run; the fold layout (5 folds of 1 s blocks)
# was chosen on seeds 101-102 only (over 3 s and 10 s blocks). CV_ARGS passes
# fold options to every tune (e.g. CV_ARGS="--cv-block 10"). Writes
# OUT_DIR/runs.csv (one row per robot, seed, model) and OUT_DIR/summary.md.
# Needs build/odotune and python3; about 15 s.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-out/fix-cv-study}
SEEDS=${2:-"201 202 203"}
BIN=${BIN:-build/odotune}
PSO=(--particles 20 --iterations 40 --seed 1)
mkdir -p "$OUT/tracks" "$OUT/json"

make_track() {  # NAME SEED → path
  local name=$1 seed=$2 t="$OUT/tracks/$1-$2.csv"
  case $name in
    track*) "$BIN" simulate "scenarios/$name.yaml" --seed "$seed" -o "$t" > /dev/null ;;
    wheelchair)
      "$BIN" simulate scenarios/wheelchair.yaml --seed "$seed" -o "$t.raw" > /dev/null
      "$BIN" fixes "$t.raw" -o "$t" --rate-hz 1 --sigma-m 0.10 --seed "$seed" --no-variances > /dev/null
      rm -f "$t.raw" ;;
    slow_robot)
      "$BIN" simulate scenarios/slow_robot.yaml --seed "$seed" -o "$t.raw" > /dev/null
      "$BIN" fixes "$t.raw" -o "$t" --rate-hz 2 --sigma-m 0.02 --seed "$seed" --no-variances > /dev/null
      rm -f "$t.raw" ;;
  esac
  echo "$t"
}

echo "robot,seed,model,baseline_rmse_m,gt_tuned_rmse_m,mode8_rmse_m,mode9_rmse_m,mode8_ratio,mode9_ratio" \
  > "$OUT/runs.csv"
for robot in track1 track2 track3 track4 track5 wheelchair slow_robot; do
  for seed in $SEEDS; do
    t=$(make_track "$robot" "$seed")
    for model in rq alpha gyro; do
      for mode in 1 8 9; do
        "$BIN" tune --track "$t" --model "$model" --mode "$mode" "${PSO[@]}" ${CV_ARGS:-} \
          --json "$OUT/json/$robot-$seed-$model-$mode.json" > /dev/null
      done
      python3 - "$OUT/json/$robot-$seed-$model" "$robot" "$seed" "$model" >> "$OUT/runs.csv" <<'PY'
import json, sys
stem, robot, seed, model = sys.argv[1:5]
m1 = json.load(open(f"{stem}-1.json"))["tracks"][0]
m8 = json.load(open(f"{stem}-8.json"))["tracks"][0]
m9 = json.load(open(f"{stem}-9.json"))["tracks"][0]
gt = m1["tuned"]["rmse_m"]
r8 = m8["ground_truth_tuned"]["rmse_m"]
r9 = m9["ground_truth_tuned"]["rmse_m"]
print(f"{robot},{seed},{model},{m1['baseline']['rmse_m']:.6f},{gt:.6f},{r8:.6f},{r9:.6f},{r8 / gt:.4f},{r9 / gt:.4f}")
PY
    done
  done
  echo "  $robot done" >&2
done

python3 - "$OUT" <<'PY'
import csv, sys, statistics
out = sys.argv[1]
rows = list(csv.DictReader(open(f"{out}/runs.csv")))
lines = ["| robot | model | runs | ground-truth tune RMSE (mean) | mode 8: ratio mean / worst | mode 9: ratio mean / worst |",
         "|---|---|---:|---:|---:|---:|"]
for robot in dict.fromkeys(r["robot"] for r in rows):
    for model in ("rq", "alpha", "gyro"):
        rs = [r for r in rows if r["robot"] == robot and r["model"] == model]
        if not rs: continue
        r8 = [float(r["mode8_ratio"]) for r in rs]
        r9 = [float(r["mode9_ratio"]) for r in rs]
        gt = statistics.mean(float(r["gt_tuned_rmse_m"]) for r in rs)
        lines.append(f"| {robot} | {model} | {len(rs)} | {gt * 1000:.1f} mm | {statistics.mean(r8):.3f} / {max(r8):.3f} "
                     f"| {statistics.mean(r9):.3f} / {max(r9):.3f} |")
r8 = [float(r["mode8_ratio"]) for r in rows]
r9 = [float(r["mode9_ratio"]) for r in rows]
lines.append("")
lines.append(f"All {len(rows)} tunes: mode 8 within 10 % of the ground-truth tune in {sum(x <= 1.10 for x in r8)}, "
             f"mean ratio {statistics.mean(r8):.3f}, worst {max(r8):.3f}; mode 9 within 10 % in "
             f"{sum(x <= 1.10 for x in r9)}, mean ratio {statistics.mean(r9):.3f}, worst {max(r9):.3f}.")
open(f"{out}/summary.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
