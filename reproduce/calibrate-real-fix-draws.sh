#!/usr/bin/env bash
# Protocol A of docs/calibration/real-data.md (calibrate on three OptiOdom runs,
# replay four others) for online-pose and for the pose fit on the same fixes
# (batch-pose-fixes), repeated over several draws of the fixes' noise: how much
# of the gap to the pose fit on OptiTrack is the method's and how much the draw's.
#   bash reproduce/calibrate-real-fix-draws.sh [OUT_DIR] [DRAWS]
# (default out/calibration-real-draws, 10 draws). Draw d gives run k the noise
# seed 100·d + k (draw 0 is calibrate-real.sh's). Needs the imported tracks of
# reproduce/calibrate-real.sh in out/calibration-real/tracks (run it first),
# build/odotune and python3. Writes OUT_DIR/draws.csv and prints the summary.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-build/odotune}
OUT=${1:-out/calibration-real-draws}
DRAWS=${2:-10}
TR=${TRACKS:-out/calibration-real/tracks}
CAL=(optiodom-231220200146-run-01 optiodom-231220200045-run-01 optiodom-030120210001-run-01)
HELD=(optiodom-231220200146-run-02 optiodom-231220200045-run-02 optiodom-020120212354-run-01
      optiodom-030120210001-run-02)
mkdir -p "$OUT"
echo "draw,method,heldout_mean_pose_rmse_m,heldout_better_than_nominal" > "$OUT/draws.csv"
for ((d = 0; d < DRAWS; d++)); do
  k=0
  for r in "${CAL[@]}" "${HELD[@]}"; do
    k=$((k + 1))
    "$BIN" fixes "$TR/$r.csv" -o "$OUT/$r-fixes.csv" --seed $((100 * d + k)) > /dev/null
    python3 reproduce/strip_ground_truth.py "$OUT/$r-fixes.csv" "$OUT/$r-fixes-only.csv"
  done
  held=()
  for r in "${HELD[@]}"; do held+=(--track "$TR/$r.csv"); done
  for m in online-pose batch-pose-fixes; do
    args=()
    if [ "$m" = online-pose ]; then
      for r in "${CAL[@]}"; do args+=(--track "$OUT/$r-fixes.csv"); done
      args+=(--method online-pose --fix-sigma-m 0.06)
    else
      for r in "${CAL[@]}"; do args+=(--track "$OUT/$r-fixes-only.csv"); done
      args+=(--method batch-pose)
    fi
    "$BIN" calibrate "${args[@]}" --config-out "$OUT/$m-$d.yaml" > /dev/null
    "$BIN" calibrate --apply "$OUT/$m-$d.yaml" "${held[@]}" --json "$OUT/$m-$d.json" > /dev/null
    python3 - "$OUT/$m-$d.json" "$d" "$m" >> "$OUT/draws.csv" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
cal = [t["calibrated"]["pose_rmse_m"] for t in j["tracks"]]
nom = [t["nominal"]["pose_rmse_m"] for t in j["tracks"]]
print(f"{sys.argv[2]},{sys.argv[3]},{sum(cal) / len(cal):.5f},{sum(c < n for c, n in zip(cal, nom))}/{len(cal)}")
PY
  done
done
python3 - "$OUT/draws.csv" <<'PY'
import csv, sys, statistics as st
rows = list(csv.DictReader(open(sys.argv[1])))
for m in ("online-pose", "batch-pose-fixes"):
    v = [1000 * float(r["heldout_mean_pose_rmse_m"]) for r in rows if r["method"] == m]
    allbetter = sum(r["heldout_better_than_nominal"] == "4/4" for r in rows if r["method"] == m)
    print(f"{m}: held-out mean over {len(v)} draws {st.mean(v):.1f} mm (median {st.median(v):.1f}, "
          f"{min(v):.1f}-{max(v):.1f}); all four held-out runs better than nominal in {allbetter}/{len(v)}")
PY
