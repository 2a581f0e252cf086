#!/usr/bin/env bash
# robot_localization's own EKF on the Husky recording (test1 of its tests),
# tuned without ground truth and exported as the robot's parameter file
# (docs/husky.md reports what this writes):
#   1. the filter as robot_localization's bag1 test runs it (its final pose);
#   2. the user's file (husky_ekf.yaml: wheel velocities, the IMU's roll,
#      pitch, rates and accelerations, the GPS through navsat_transform_node)
#      with robot_localization's default noise, and with the process noise of
#      the old 3-state export (docs/husky/ekf-rq.yaml), scored on the second
#      half: a GPS outage from the midpoint, and every 5th fix held out;
#   3. the tune on the first half only (t < 197.65 s), which writes
#      OUT/ekf.yaml, the user's file with the tuned values;
#   4. that file replayed as written: the second half's figures again;
#   5. the trajectories over the fixes (figure, TUM files for evo).
#   bash reproduce/husky-rl.sh [OUT_DIR]        (default out/husky-rl)
# Needs build/odotune (bash scripts/build.sh) and gnuplot. BIN and REAL as in
# reproduce/husky-no-gt.sh. About 10 minutes on 2 cores (the tune).
#
# The IMU's mounting is robot_localization's ROS 1 test's (the bag has no
# /tf_static): x 0, y −0.3, z 0.52 m, roll π/2, pitch 0, yaw −π/2. The IMU's
# absolute yaw is 115–160° off the GPS course here, so navsat's rotation is
# fitted on the first 60 s of fixes (--gps-heading-fit).
# The tune's settings (fitness both, a factor per diagonal entry, no input-covariance
# factors, outages of 60 s) were chosen on the first half alone: tuned on its
# first quarter of the drive, compared on its second (docs/husky.md).
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
OUT=${1:-out/husky-rl}
BIN=${BIN:-build/odotune}
BAGS=$REAL/robot_localization_bags
TF=imu_link=0,-0.3,0.52,1.5707963267948966,0,-1.5707963267948966
MID=197.65
SRC=(--bag "$BAGS/test1.bag" --tf "$TF" --gps-heading-fit 60)
mkdir -p "$OUT"

echo "== 1. robot_localization's bag1 test configuration" >&2
cat > "$OUT/bag1-test.yaml" <<'YAML'
# robot_localization's test/test_ekf_localization_node_bag1.yaml (its ekf node's keys that change the estimate)
test_ekf_localization_node_bag1_ekf:
  ros__parameters:
    frequency: 30.0
    sensor_timeout: 0.1
    two_d_mode: false
    odom0: /husky_velocity_controller/odom
    imu0: /imu/data
    odom0_config: [false, false, false, false, false, false, true, true, true, false, false, false, false, false, false]
    imu0_config: [false, false, false, true, true, true, false, false, false, true, true, false, true, true, true]
    imu0_remove_gravitational_acceleration: true
YAML
"$BIN" eval --rl-params "$OUT/bag1-test.yaml" --bag "$BAGS/test1.bag" --tf "$TF" | tee "$OUT/bag1-test.txt"

echo "== 2. defaults and the old 3-state export, scored on the second half" >&2
"$BIN" eval --rl-params "$BAGS/husky_ekf.yaml" "${SRC[@]}" --from $MID --json "$OUT/defaults.json" \
  --trajectory-out "$OUT/defaults.tum" --fixes-out "$OUT/fixes.txt" | tee "$OUT/defaults.txt"
"$BIN" eval --rl-params "$BAGS/husky_ekf.yaml" "${SRC[@]}" --from $MID --noise-from docs/husky/ekf-rq.yaml \
  --json "$OUT/old-export.json" --trajectory-out "$OUT/old-export.tum" | tee "$OUT/old-export.txt"

echo "== 3. tune on the first half (t < $MID s)" >&2
"$BIN" tune --rl-params "$BAGS/husky_ekf.yaml" "${SRC[@]}" --until $MID --fitness both --space diagonal \
  --no-input-covariances --seed 1 --particles 50 --iterations 150 --config-out "$OUT/ekf.yaml" \
  --config-out-ros1 "$OUT/ekf-ros1.yaml" --json "$OUT/tune.json" | tee "$OUT/tune.txt"

echo "== 4. the written file, replayed as written" >&2
"$BIN" eval --rl-params "$OUT/ekf.yaml" "${SRC[@]}" --from $MID --json "$OUT/tuned.json" \
  --trajectory-out "$OUT/tuned.tum" | tee "$OUT/tuned.txt"

echo "== 5. figure" >&2
if command -v gnuplot > /dev/null; then
  gnuplot <<GP
set terminal pngcairo size 1100,800 noenhanced
set output "$OUT/trajectories.png"
set title "Husky (robot_localization test1): robot_localization's EKF, GPS fused until $MID s only"
set xlabel "x [m] (odom)"; set ylabel "y [m] (odom)"; set size ratio -1; set key outside bottom center horizontal
plot "$OUT/fixes.txt" using 2:3 with points pt 7 ps 0.3 lc rgb "#999999" title "GPS fixes", \
     "$OUT/defaults.tum" using 2:3 with lines lw 1.5 lc rgb "#d62728" title "defaults", \
     "$OUT/old-export.tum" using 2:3 with lines lw 1.5 lc rgb "#ff7f0e" title "old 3-state export", \
     "$OUT/tuned.tum" using 2:3 with lines lw 2 lc rgb "#1f77b4" title "tuned (ekf.yaml)"
GP
fi
echo "wrote $OUT/ekf.yaml (ROS 2) and $OUT/ekf-ros1.yaml (ROS 1)" >&2
