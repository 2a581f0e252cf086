#!/usr/bin/env bash
# Held-out calibration when the robot differs from run to run: a simulated
# study of what docs/calibration/real-data.md ("Run-to-run variation") reports.
#
# Twelve runs of scenarios/slow_robot.yaml (a 0.1 m/s robot, R = 42 mm,
# D = 0.2 m), each with its own geometry: radius scales 0.999·(1 + c + e) per
# wheel with a common c ~ N(0, 0.1 %) and e ~ N(0, 0.1 %) per wheel, wheel-base
# scale 1.01·(1 + N(0, 1 %)); that is, a mean offset from the nominal values
# about the size of the run-to-run spread, as the per-run pose fits of the
# OptiOdom runs show (D from 0.1943 to 0.2021 m). The draws are seeded
# (python3's random, seed 777; noise seeds 401–412), so the study repeats.
# Three splits, each calibrating on three runs and replaying four others,
# like protocol A of reproduce/calibrate-real.sh:
#   bash reproduce/calibrate-run-variation.sh [OUT_DIR]  (default out/calibration-run-variation)
# Writes OUT_DIR/runs.csv (each run's true scales), OUT_DIR/heldout.csv (one
# row per split, method and held-out run) and OUT_DIR/summary.md (the table).
# Needs build/odotune (bash scripts/build.sh) and python3; about 6 s.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-out/calibration-run-variation}
BIN=${BIN:-build/odotune}
mkdir -p "$OUT/tracks" "$OUT/fits"

python3 - "$OUT" <<'PY' > "$OUT/runs.csv"
import random, sys
rng = random.Random(777)
print("run,noise_seed,scale_l,scale_r,base_scale")
for k in range(1, 13):
    c = rng.gauss(0, 0.001)
    sl = 0.999 * (1 + c + rng.gauss(0, 0.001))
    sr = 0.999 * (1 + c + rng.gauss(0, 0.001))
    sd = 1.01 * (1 + rng.gauss(0, 0.01))
    print(f"{k},{400 + k},{sl:.6f},{sr:.6f},{sd:.6f}")
PY
while IFS=, read -r run seed sl sr sd; do
  [ "$run" = run ] && continue
  "$BIN" simulate scenarios/slow_robot.yaml -o "$OUT/tracks/r$run.csv" --seed "$seed" \
    --effect "radius_error:scale_l=$sl,scale_r=$sr" --effect "wheel_base_error:scale=$sd" > /dev/null
done < "$OUT/runs.csv"

SPLITS=("1 2 3|4 5 6 7" "5 6 7|8 9 10 11" "9 10 11|12 1 2 3")
METHODS=(batch-pose batch-velocity adaptive-pf pf dkf)
echo "split,method,heldout_run,nominal_pose_rmse_m,calibrated_pose_rmse_m" > "$OUT/heldout.csv"
for s in "${!SPLITS[@]}"; do
  cal=${SPLITS[$s]%|*}
  held=${SPLITS[$s]#*|}
  cal_args=()
  for r in $cal; do cal_args+=(--track "$OUT/tracks/r$r.csv"); done
  held_args=()
  for r in $held; do held_args+=(--track "$OUT/tracks/r$r.csv"); done
  for m in "${METHODS[@]}"; do
    extra=()
    [ "$m" != batch-pose ] && extra=(--ext-from-gt 10)
    stem="$OUT/fits/split$((s + 1))-$m"
    "$BIN" calibrate "${cal_args[@]}" --method "$m" "${extra[@]}" --seed 1 --threads 1 \
      --config-out "$stem.yaml" > "$stem.txt"
    "$BIN" calibrate "${held_args[@]}" --apply "$stem.yaml" --json "$stem-heldout.json" > /dev/null
    python3 - "$((s + 1))" "$m" "$stem-heldout.json" >> "$OUT/heldout.csv" <<'PY'
import json, sys
split, method, path = sys.argv[1:4]
for t in json.load(open(path))["tracks"]:
    print(f'{split},{method},{t["track"]},{t["nominal"]["pose_rmse_m"]:.5f},{t["calibrated"]["pose_rmse_m"]:.5f}')
PY
  done
  echo "  split $((s + 1)) done" >&2
done

python3 - "$OUT" <<'PY'
import csv, sys
out = sys.argv[1]
rows = list(csv.DictReader(open(f"{out}/heldout.csv")))
splits = list(dict.fromkeys(r["split"] for r in rows))
methods = list(dict.fromkeys(r["method"] for r in rows))
lines = ["| method | " + " | ".join(f"split {s}: mean (runs better)" for s in splits) + " |",
         "|---|" + "---:|" * len(splits)]
nominal = []
for s in splits:
    rs = [r for r in rows if r["split"] == s and r["method"] == methods[0]]
    nominal.append(sum(1000 * float(r["nominal_pose_rmse_m"]) for r in rs) / len(rs))
lines.append("| none | " + " | ".join(f"{n:.1f} mm" for n in nominal) + " |")
for m in methods:
    cells = []
    for s in splits:
        rs = [r for r in rows if r["split"] == s and r["method"] == m]
        mean = sum(1000 * float(r["calibrated_pose_rmse_m"]) for r in rs) / len(rs)
        better = sum(float(r["calibrated_pose_rmse_m"]) < float(r["nominal_pose_rmse_m"]) for r in rs)
        cells.append(f"{mean:.1f} mm ({better}/{len(rs)})")
    lines.append(f"| {m} | " + " | ".join(cells) + " |")
open(f"{out}/summary.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
