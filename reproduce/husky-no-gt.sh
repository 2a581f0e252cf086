#!/usr/bin/env bash
# The Husky recording of robot_localization's own tests, end to end, without
# ground truth (docs/husky.md reports what this writes):
#   1. import test1 from its three forms (ROS 1 .bag, MCAP, rosbag2 SQLite)
#      and check they give the same track (the ROS 1 form when this build
#      reads ROS 1 bags);
#   2. tune the EKF noise of the three models by fix cross-validation (mode 8,
#      no ground truth) in a grid store on the first half of the drive
#      (t < 197 s), and report it;
#   3. export each tuned model as a robot_localization parameter file;
#   4. score baseline and tuned noise on the second half, which the tune never
#      saw (its held-out fixes); the trajectories of the whole drive (TUM, for
#      evo) and a figure;
#   5. diagnose the recording with the fixes as the reference.
#   bash reproduce/husky-no-gt.sh [OUT_DIR]        (default out/husky)
# Needs build/odotune (bash scripts/build.sh), python3 and gnuplot.
#
# The IMU's mounting rotation is robot_localization's ROS 1 test's
# (test_ekf_localization_node_bag1.test: static_transform_publisher
# "0 -0.3 0.52 -1.570796327 0 1.570796327", i.e. yaw −π/2, pitch 0,
# roll π/2); with it the gyro follows the wheel odometry's yaw rate
# (tests/tracks/test_import_rosbag.cpp).
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
OUT=${1:-out/husky}
BIN=${BIN:-build/odotune}
BAGS=$REAL/robot_localization_bags
RPY=1.5707963267948966,0,-1.5707963267948966
mkdir -p "$OUT"

echo "== import" >&2
"$BIN" import rosbag "$BAGS/ros2/test1.mcap" --imu-rpy "$RPY" -o "$OUT/husky.csv" | tee "$OUT/import.txt"
"$BIN" import rosbag "$BAGS/ros2/test1_db3" --imu-rpy "$RPY" -o "$OUT/husky-db3.csv" > /dev/null
forms="MCAP, rosbag2 SQLite"
if "$BIN" import rosbag "$BAGS/test1.bag" --imu-rpy "$RPY" -o "$OUT/husky-ros1.csv" > /dev/null 2>&1; then
  forms="ROS 1, $forms"
fi
# The data rows (not the metadata, which names each source) must be identical.
for f in "$OUT"/husky-db3.csv "$OUT"/husky-ros1.csv; do
  [ -f "$f" ] || continue
  if ! cmp -s <(grep -v '^#' "$OUT/husky.csv") <(grep -v '^#' "$f"); then
    echo "husky-no-gt: $f differs from $OUT/husky.csv" >&2
    exit 1
  fi
done
echo "identical tracks from: $forms" | tee -a "$OUT/import.txt"
# The two halves of the drive: tuned on the first, scored on the second.
python3 - "$OUT" <<'PY'
import sys
out = sys.argv[1]
lines = open(f"{out}/husky.csv").read().splitlines(keepends=True)
meta = [l for l in lines if l.startswith("#")]
rest = [l for l in lines if not l.startswith("#")]
header, rows = rest[0], rest[1:]
half = float(rows[-1].split(",")[0]) / 2
for name, part in (("first", [r for r in rows if float(r.split(",")[0]) < half]),
                   ("second", [r for r in rows if float(r.split(",")[0]) >= half])):
    with open(f"{out}/husky-{name}-half.csv", "w") as f:
        f.writelines([m.replace("# name: test1.mcap", f"# name: husky-{name}-half") for m in meta])
        f.write(f"# split: the {name} half of the drive (t {'<' if name == 'first' else '≥'} {half:.3f} s)\n")
        f.write(header)
        f.writelines(part)
PY

echo "== tune (grid, mode 8) and report" >&2
track_abs=$(realpath "$OUT/husky-first-half.csv")
store_abs=$(realpath "$OUT")/husky.sqlite
rm -f "$store_abs"
cat > "$OUT/husky-experiment.yaml" <<EOF
format: odotune-experiment/1
name: husky-no-ground-truth
# robot_localization's Husky (test1), the first half of the drive: odometry
# twist, IMU yaw rate, GPS fixes.
# Mode 8 scores each noise by the prediction error of held-out fixes
# (odotune/objectives/fix_cv_replay.h): the recording has no ground truth.
models: [rq, alpha, gyro]
tracks: [$track_abs]
modes: [8]
seeds: [1, 2, 3]
solver: pso
budget: {particles: 30, iterations: 60}
leave_one_out: false
store: $store_abs
EOF
"$BIN" grid "$OUT/husky-experiment.yaml" > "$OUT/grid.txt"
"$BIN" report "$store_abs" --mode 8 --out "$OUT/report" > "$OUT/report.txt"
for m in rq alpha gyro; do
  "$BIN" export "$store_abs" --select mode=8 --select model=$m --format robot_localization \
    --out "$OUT/ekf-$m.yaml" | tee -a "$OUT/export.txt"
  "$BIN" export "$store_abs" --select mode=8 --select model=$m --format odotune --out "$OUT/odotune-$m.yaml" \
    > /dev/null
done

echo "== the second half (never seen by the tune) and trajectories" >&2
best=$(python3 - "$OUT/export.txt" <<'PY'
import re, sys
best = min(((float(re.search(r"tuned RMSE ([0-9.]+) mm", l).group(1)), re.match(r"exported run (\w+)\|", l).group(1))
            for l in open(sys.argv[1]) if l.startswith("exported run")))
print(best[1])
PY
)
: > "$OUT/heldout.txt"
for m in rq alpha gyro; do
  "$BIN" eval --config "$OUT/odotune-$m.yaml" --track "$OUT/husky-second-half.csv" --json "$OUT/heldout-$m.json" \
    | tee -a "$OUT/heldout.txt"
done
"$BIN" eval --track "$OUT/husky.csv" --trajectory-out "$OUT/baseline.tum" > /dev/null
"$BIN" eval --config "$OUT/odotune-$best.yaml" --track "$OUT/husky.csv" --trajectory-out "$OUT/tuned-$best.tum" \
  > /dev/null

# The fixes and both trajectories on one plot (gnuplot), from the TUM files.
python3 - "$OUT" "$best" <<'PY'
import csv, sys
out, best = sys.argv[1:3]
rows = [r for r in csv.DictReader(l for l in open(f"{out}/husky.csv") if not l.startswith("#"))]
with open(f"{out}/fixes.dat", "w") as f:
    for r in rows:
        if r["aps_x"]:
            f.write(f"{r['aps_x']} {r['aps_y']}\n")
for name in ("baseline", f"tuned-{best}"):
    with open(f"{out}/{name}.dat", "w") as f:
        for l in open(f"{out}/{name}.tum"):
            if not l.startswith("#"):
                p = l.split()
                f.write(f"{p[1]} {p[2]}\n")
PY
# Innovations: each fix against the filter's pose just before it (the state
# after the previous row, which has not seen that fix), on the whole drive.
python3 - "$OUT" "$best" <<'PY'
import bisect, csv, math, sys
out, best = sys.argv[1:3]
rows = [r for r in csv.DictReader(l for l in open(f"{out}/husky.csv") if not l.startswith("#"))]
t0 = next(int(l.split(":")[1]) * 1e-9 for l in open(f"{out}/husky.csv") if l.startswith("# source.t0_ns:"))
for name in ("baseline", f"tuned-{best}"):
    traj = [l.split() for l in open(f"{out}/{name}.tum") if not l.startswith("#")]
    times = [float(p[0]) - t0 for p in traj]
    with open(f"{out}/innovations-{name}.dat", "w") as f:
        for r in rows:
            if not r["aps_x"]:
                continue
            t = float(r["t"])
            i = bisect.bisect_left(times, t - 1e-6) - 1
            if i < 0:
                continue
            x, y = float(traj[i][1]), float(traj[i][2])
            f.write(f"{t:.3f} {math.hypot(float(r['aps_x']) - x, float(r['aps_y']) - y):.4f}\n")
PY
if command -v gnuplot > /dev/null; then
  half=$(grep "^# split" "$OUT/husky-second-half.csv" | sed 's/.*≥ \([0-9.]*\) s.*/\1/')
  gnuplot <<EOF
set terminal pngcairo size 1100,450 noenhanced
set output "$OUT/husky_innovations.png"
set xlabel "t [s]"; set ylabel "|fix − predicted position| [m]"
set title "Husky: each GPS fix against the filter's prediction before it; tuned on t < $half s (shaded: never seen by the tune)"
set object 1 rect from $half, graph 0 to graph 1, graph 1 fc rgb "#eeeeee" behind
set key top left
plot "$OUT/innovations-baseline.dat" w l lc rgb "#1f77b4" t "baseline EKF", \\
     "$OUT/innovations-tuned-$best.dat" w l lc rgb "#d62728" t "tuned EKF ($best)"
EOF
  gnuplot <<EOF
set terminal pngcairo size 900,900 noenhanced
set output "$OUT/husky_trajectories.png"
set size ratio -1
set xlabel "east [m]"; set ylabel "north [m]"
set title "Husky (robot_localization test1): GPS fixes, baseline and tuned EKF ($best, mode 8)"
set key bottom right
plot "$OUT/fixes.dat" w p pt 7 ps 0.3 lc rgb "#999999" t "GPS fixes (σ ≈ 0.9 m)", \
     "$OUT/baseline.dat" w l lw 2 lc rgb "#1f77b4" t "baseline EKF", \
     "$OUT/tuned-$best.dat" w l lw 1.5 lc rgb "#d62728" t "tuned EKF ($best)"
EOF
fi

echo "== diagnose (fixes as reference)" >&2
"$BIN" diagnose "$OUT/husky.csv" --json "$OUT/diagnosis.json" > "$OUT/diagnosis.txt"
cat "$OUT/diagnosis.txt"
