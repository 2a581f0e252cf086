#!/usr/bin/env bash
# Odometry calibration on the real OptiOdom recordings of
# ../shared/data/real/optiodom_diff (SOURCE.md there: Sousa et al., JINT 2022,
# MIT licence), every method under the two held-out protocols that
# docs/calibration/real-data.md reports:
#   A  calibrate on three runs, replay four other runs with the result;
#   B  leave one run out: for each of the seven runs, calibrate on the other
#      six and replay it.
#   bash reproduce/calibrate-real.sh [OUT_DIR]      (default out/calibration-real)
# Writes OUT_DIR/summary.md (the tables), OUT_DIR/heldout.csv (one row per
# protocol, method and held-out run), OUT_DIR/heldout_paths.png/.svg (the
# held-out trajectories of protocol A) and each run's JSON/YAML. Needs
# build/odotune (bash scripts/build.sh), python3 and gnuplot.
#
# The robot has no velocity sensor: the online methods and batch-velocity
# use body velocities derived from the OptiTrack poses at 10 Hz
# (--ext-from-gt 10), a stand-in for scan matching, whose noise odotune
# estimates from the poses' own jitter (odotune/calibration/reference_jitter.h). The
# pose fit (batch-pose, the default batch) uses the poses themselves.
#
# online-pose, the online filter of position fixes, runs on copies of the
# runs with fixes made from the OptiTrack poses by `odotune fixes` at its
# defaults (1 Hz, σ 60 mm), and starts from the fixes alone (the OptiTrack
# poses only score it). batch-pose-fixes is the pose fit on the same fixes
# with the OptiTrack columns removed: the offline optimum of that information.
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
OUT=${1:-out/calibration-real}
BIN=${BIN:-build/odotune}
OO=$REAL/optiodom_diff
mkdir -p "$OUT/tracks" "$OUT/fixes" "$OUT/fixes-only" "$OUT/A" "$OUT/B"

import() {  # relative run path without .csv, run number → prints the imported track path
  local name
  name=optiodom-$(basename "$1" | tr '_' '-')
  "$BIN" import optiodom "$OO/$1.csv" -o "$OUT/tracks/$name.csv" > /dev/null
  # The fixes' noise seed is the run's number (one draw per run, not the same on all).
  "$BIN" fixes "$OUT/tracks/$name.csv" -o "$OUT/fixes/$name.csv" --seed "$2" > /dev/null
  python3 reproduce/strip_ground_truth.py "$OUT/fixes/$name.csv" "$OUT/fixes-only/$name.csv"
  echo "$OUT/tracks/$name.csv"
}

CAL=()
run=0
for r in circular/231220200146/231220200146_run-01 square/231220200045/231220200045_run-01 \
         free/030120210001/030120210001_run-01; do
  run=$((run + 1))
  CAL+=("$(import "$r" "$run")")
done
HELD=()
for r in circular/231220200146/231220200146_run-02 square/231220200045/231220200045_run-02 \
         free/020120212354/020120212354_run-01 free/030120210001/030120210001_run-02; do
  run=$((run + 1))
  HELD+=("$(import "$r" "$run")")
done
ALL=("${CAL[@]}" "${HELD[@]}")

METHODS=(none batch-pose batch-velocity adaptive-pf pf dkf online-pose batch-pose-fixes)
calibrate() {  # OUT_STEM METHOD TRACK... → OUT_STEM.yaml, OUT_STEM.json, prints wall seconds
  local stem=$1 method=$2
  shift 2
  local args=() extra=() folder=""
  case $method in
    batch-pose | none) ;;
    online-pose) folder=fixes extra=(--fix-sigma-m 0.06) ;;
    batch-pose-fixes) folder=fixes-only method=batch-pose ;;
    *) extra=(--ext-from-gt 10) ;;
  esac
  for t in "$@"; do
    [ -n "$folder" ] && t=${t/\/tracks\//\/$folder\/}
    args+=(--track "$t")
  done
  local t0 t1
  t0=$(date +%s.%N)
  "$BIN" calibrate "${args[@]}" --method "$method" "${extra[@]}" --seed 1 --threads 1 \
    --json "$stem.json" --config-out "$stem.yaml" > "$stem.txt"
  t1=$(date +%s.%N)
  python3 -c "print(f'{$t1 - $t0:.2f}')"
}
apply() {  # CALIBRATION_YAML OUT_JSON [PATHS_CSV] TRACK...
  local cal=$1 json=$2 paths=$3
  shift 3
  local args=()
  for t in "$@"; do args+=(--track "$t"); done
  local extra=()
  [ -n "$paths" ] && extra=(--paths-csv "$paths")
  "$BIN" calibrate "${args[@]}" --apply "$cal" --json "$json" "${extra[@]}" > /dev/null
}

echo "protocol,method,heldout_run,nominal_pose_rmse_m,calibrated_pose_rmse_m,calibration_wall_s,r_l_m,r_r_m,d_m" \
  > "$OUT/heldout.csv"
row() {  # PROTOCOL METHOD APPLY_JSON WALL CAL_YAML
  python3 - "$@" >> "$OUT/heldout.csv" <<'PY'
import json, sys, re
proto, method, path, wall, cal = sys.argv[1:6]
j = json.load(open(path))
text = open(cal).read()
def val(k):
    return re.search(rf"^{k}:\s*([0-9.eE+-]+)", text, re.M).group(1)
for t in j["tracks"]:
    print(f'{proto},{method},{t["track"]},{t["nominal"]["pose_rmse_m"]:.5f},'
          f'{t["calibrated"]["pose_rmse_m"]:.5f},{wall},{val("wheel_radius_left_m")},'
          f'{val("wheel_radius_right_m")},{val("wheel_base_m")}')
PY
}

echo "== protocol A: calibrate on ${#CAL[@]} runs, replay ${#HELD[@]}" >&2
for m in "${METHODS[@]}"; do
  wall=$(calibrate "$OUT/A/$m" "$m" "${CAL[@]}")
  apply "$OUT/A/$m.yaml" "$OUT/A/$m-heldout.json" "$OUT/A/$m-paths.csv" "${HELD[@]}"
  row A "$m" "$OUT/A/$m-heldout.json" "$wall" "$OUT/A/$m.yaml"
  echo "  $m: ${wall} s" >&2
done

echo "== protocol B: leave one of ${#ALL[@]} runs out" >&2
for m in "${METHODS[@]}"; do
  for held in "${ALL[@]}"; do
    fit=()
    for t in "${ALL[@]}"; do [ "$t" != "$held" ] && fit+=("$t"); done
    name=$(basename "$held" .csv)
    wall=$(calibrate "$OUT/B/$m-$name" "$m" "${fit[@]}")
    apply "$OUT/B/$m-$name.yaml" "$OUT/B/$m-$name-heldout.json" "" "$held"
    row B "$m" "$OUT/B/$m-$name-heldout.json" "$wall" "$OUT/B/$m-$name.yaml"
  done
  echo "  $m done" >&2
done

python3 - "$OUT" <<'PY'
import csv, sys, collections
out = sys.argv[1]
rows = list(csv.DictReader(open(f"{out}/heldout.csv")))
lines = []
for proto, title in (("A", "Protocol A: calibrated on 3 runs, held out on 4"),
                     ("B", "Protocol B: leave one run out (7 calibrations per method)")):
    rs = [r for r in rows if r["protocol"] == proto]
    runs = list(dict.fromkeys(r["heldout_run"] for r in rs))
    methods = list(dict.fromkeys(r["method"] for r in rs))
    lines.append(f"### {title}\n")
    short = [r.replace("optiodom-", "") for r in runs]
    lines.append("| method | " + " | ".join(short) + " | mean | runs better than nominal | calibration wall time |")
    lines.append("|---|" + "---:|" * (len(runs) + 3))
    for m in methods:
        mr = {r["heldout_run"]: r for r in rs if r["method"] == m}
        vals = [1000 * float(mr[r]["calibrated_pose_rmse_m"]) for r in runs]
        nom = [1000 * float(mr[r]["nominal_pose_rmse_m"]) for r in runs]
        better = sum(v < n for v, n in zip(vals, nom))
        walls = [float(mr[r]["calibration_wall_s"]) for r in runs]
        wall = f"{walls[0]:.2f} s" if proto == "A" else f"{sum(walls) / len(walls):.2f} s per fit"
        lines.append(f"| {m} | " + " | ".join(f"{v:.1f}" for v in vals) +
                     f" | **{sum(vals) / len(vals):.1f}** | {better}/{len(runs)} | {wall} |")
    lines.append("")
open(f"{out}/summary.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY

# Held-out trajectories of protocol A: OptiTrack, nominal, each calibration.
if command -v gnuplot > /dev/null; then
  plot=""
  i=0
  for h in "${HELD[@]}"; do
    name=$(basename "$h" .csv)
    i=$((i + 1))
    plot+="set title '${name#optiodom-} (held out)'; plot "
    plot+="'< grep ^$name, $OUT/A/none-paths.csv' using 3:4 with lines lw 2 lc rgb 'black' title 'OptiTrack', "
    plot+="'' using 5:6 with lines lc rgb 'gray50' dt 2 title 'nominal'"
    for m in batch-pose batch-velocity adaptive-pf pf dkf online-pose; do
      plot+=", '< grep ^$name, $OUT/A/$m-paths.csv' using 7:8 with lines title '$m'"
    done
    plot+=$'\n'
  done
  for term in "pngcairo size 1400,1100" "svg size 1400,1100"; do
    ext=${term%% *}; ext=${ext%cairo}
    gnuplot <<GP
set terminal $term
set output '$OUT/heldout_paths.$ext'
set datafile separator ','
set multiplot layout 2,2 title 'OptiOdom held-out runs (protocol A): dead reckoning with each calibration'
set size ratio -1
set key bottom right font ',8'
set xlabel 'x [m]'; set ylabel 'y [m]'
$plot
unset multiplot
GP
  done
fi
echo "wrote $OUT/summary.md, $OUT/heldout.csv, $OUT/heldout_paths.png/.svg" >&2
