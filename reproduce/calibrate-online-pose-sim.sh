#!/usr/bin/env bash
# Online pose-domain calibration (calibrate --method online-pose) on the
# simulated robots with position fixes made from their ground truth by
# `odotune fixes`: the wheelchair of the paper's Tables I-II (constant and
# with the passenger's radius step at 55 s) and the slow robot (5 min, and
# a 20 min drive of the same laps, constant and with a radius step), for
# seeds that the filter's design never used (its design seeds were 101-103).
#   bash reproduce/calibrate-online-pose-sim.sh [OUT_DIR] [SEEDS…]
# (default out/online-pose-sim, seeds 1 2 3 4 5). Writes OUT_DIR/runs.csv
# (one row per scenario, fix setting and seed), OUT_DIR/summary.md and
# OUT_DIR/wheelchair_step.png/.svg (the estimates over time, first seed).
# Needs build/odotune and python3.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-build/odotune}
OUT=${1:-out/online-pose-sim}
shift || true
SEEDS=("$@")
[ ${#SEEDS[@]} -eq 0 ] && SEEDS=(1 2 3 4 5)
mkdir -p "$OUT/tracks"
# The 20 min slow robot: the same laps, sixteen times instead of four.
sed 's/^        count: 4$/        count: 16/' scenarios/slow_robot.yaml > "$OUT/slow_robot_20min.yaml"
grep -q 'count: 16' "$OUT/slow_robot_20min.yaml"

echo "scenario,fix_rate_hz,fix_sigma_m,seed,step_t_s,convergence_s,reconvergence_s,err_l_pct,err_r_pct,err_d_pct,restarts" \
  > "$OUT/runs.csv"
run() {  # NAME SCENARIO_FILE STEP_T ("" for none) RATE SIGMA SEED
  local name=$1 file=$2 step=$3 rate=$4 sigma=$5 seed=$6
  local effect=()
  [ -n "$step" ] && effect=(--effect "radius_step:t=$step,scale_l=0.985,scale_r=0.99")
  local t="$OUT/tracks/$name-$seed.csv" f="$OUT/tracks/$name-$seed-fixes-$rate-$sigma.csv"
  [ -f "$t" ] || "$BIN" simulate "$file" --seed "$seed" "${effect[@]}" -o "$t" > /dev/null
  "$BIN" fixes "$t" -o "$f" --rate-hz "$rate" --sigma-m "$sigma" --seed "$seed" > /dev/null
  "$BIN" calibrate --track "$f" --method online-pose --fix-sigma-m "$sigma" --json "$f.json" > /dev/null
  python3 - "$f.json" "$name" "$rate" "$sigma" "$seed" "$step" >> "$OUT/runs.csv" <<'PY'
import json, sys
path, name, rate, sigma, seed, step = sys.argv[1:7]
j = json.load(open(path))
t = j["tracks"][0]
err = t["error_pct"]
conv = t.get("convergence_time_s")
rec = ([r["time_s"] for r in t.get("reconvergence") or []] or [None])[0]
print(f'{name},{rate},{sigma},{seed},{step},{"" if conv is None else conv},'
      f'{"" if rec is None else rec},{err["wheel_radius_left_m"]:.3f},'
      f'{err["wheel_radius_right_m"]:.3f},{err["wheel_base_m"]:.3f},{j.get("memory_restarts", 0)}')
PY
}
for s in "${SEEDS[@]}"; do
  run wheelchair scenarios/wheelchair.yaml "" 1 0.06 "$s"
  run wheelchair_step scenarios/wheelchair_step.yaml "" 1 0.06 "$s"
  run slow_robot scenarios/slow_robot.yaml "" 1 0.06 "$s"
  run slow_robot_20min "$OUT/slow_robot_20min.yaml" "" 1 0.06 "$s"
  run slow_robot_20min_step "$OUT/slow_robot_20min.yaml" 600 1 0.06 "$s"
  run slow_robot_20min_step "$OUT/slow_robot_20min.yaml" 600 10 0.06 "$s"
  echo "  seed $s done" >&2
done

# The estimates over time on the passenger's step, first seed (calibrate --figure).
f="$OUT/tracks/wheelchair_step-${SEEDS[0]}-fixes-1-0.06.csv"
"$BIN" calibrate --track "$f" --method online-pose --fix-sigma-m 0.06 --figure "$OUT/wheelchair_step" > /dev/null

python3 - "$OUT" <<'PY'
import csv, sys, statistics as st
out = sys.argv[1]
rows = list(csv.DictReader(open(f"{out}/runs.csv")))
keys = list(dict.fromkeys((r["scenario"], r["fix_rate_hz"], r["fix_sigma_m"]) for r in rows))
lines = ["| scenario | fixes | runs | converged within 0.5 % (radii) | convergence time | step followed | re-convergence | worst final radius error | worst final D error |",
         "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
for k in keys:
    rs = [r for r in rows if (r["scenario"], r["fix_rate_hz"], r["fix_sigma_m"]) == k]
    conv = [float(r["convergence_s"]) for r in rs if r["convergence_s"]]
    has_step = any(r["step_t_s"] for r in rs) or "wheelchair_step" == k[0]
    rec = [float(r["reconvergence_s"]) for r in rs if r["reconvergence_s"]]
    worst_r = max(max(abs(float(r["err_l_pct"])), abs(float(r["err_r_pct"]))) for r in rs)
    worst_d = max(abs(float(r["err_d_pct"])) for r in rs)
    conv_s = f"{st.mean(conv):.0f} s (max {max(conv):.0f})" if conv else "–"
    rec_s = (f"{st.mean(rec):.0f} s (max {max(rec):.0f})" if rec else "–") if has_step else ""
    lines.append(f"| {k[0]} | {k[1]} Hz, σ {float(k[2]) * 1000:.0f} mm | {len(rs)} | {len(conv)}/{len(rs)} | {conv_s} | "
                 f"{(str(len(rec)) + '/' + str(len(rs))) if has_step else ''} | {rec_s} | {worst_r:.2f} % | {worst_d:.2f} % |")
open(f"{out}/summary.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
echo "wrote $OUT/runs.csv, $OUT/summary.md" >&2
