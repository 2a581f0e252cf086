#!/usr/bin/env bash
# The Husky recording of robot_localization's own tests (test1, ../shared/data/
# real/robot_localization_bags/SOURCE.md) with its GPS fixes as the reference:
# the drive cut at its middle, the first half fitted and the second held out,
# as reproduce/diagnose-litw-halves.sh does for Lost in the Woods; the only GPS
# recording there is, so its halves stand in for two recordings.
#   bash reproduce/diagnose-husky-halves.sh [OUT_DIR]   (default out/husky-halves)
# Needs build/odotune (bash scripts/build.sh). Under a minute on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
OUT=${1:-out/husky-halves}
BIN=${BIN:-build/odotune}
# The IMU's mounting rotation of robot_localization's test (reproduce/husky-no-gt.sh).
RPY=1.5707963267948966,0,-1.5707963267948966
mkdir -p "$OUT/tracks"
T=$OUT/tracks
"$BIN" import rosbag "$REAL/robot_localization_bags/ros2/test1.mcap" --imu-rpy "$RPY" -o "$T/husky.csv" > /dev/null
BIN=$BIN bash reproduce/diagnose-track-halves.sh "$T/husky.csv" "$OUT" husky
