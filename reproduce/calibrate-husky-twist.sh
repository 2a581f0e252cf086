#!/usr/bin/env bash
# What the Husky bag of robot_localization's tests (../shared/data/real/
# robot_localization_bags, test1; SOURCE.md there) lets online-pose calibrate.
# Its wheel odometry is the controller's twist (v, w), not wheel ticks, so
# `calibrate` refuses the imported track. Mapped back to wheel rates under an
# assumed controller geometry (R_n, D_n below; the bag does not carry the
# controller's parameters), ω_l,r = (v ∓ w·D_n/2)/R_n, the calibration's
# multipliers against R_n and D_n correct the controller's own kinematics,
# whatever R_n and D_n were: the mapping is linear and inverted exactly.
#   bash reproduce/calibrate-husky-twist.sh [OUT_DIR]   (default out/husky-twist)
# Writes OUT_DIR/husky.csv (imported), husky-wheels.csv (with omega_l/omega_r),
# calibrate.txt (the refusal, then online-pose at its default memory and at
# 200 and 1000 m). Needs build/odotune and python3.
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
OUT=${1:-out/husky-twist}
BIN=${BIN:-build/odotune}
R_N=0.165  # [m], assumed
D_N=1.0    # [m], assumed (an effective separation: the Husky skid-steers)
mkdir -p "$OUT"
"$BIN" import rosbag "$REAL/robot_localization_bags/ros2/test1.mcap" \
  --imu-rpy 1.5707963267948966,0,-1.5707963267948966 -o "$OUT/husky.csv" > /dev/null
{
  echo "== the imported track as it is"
  "$BIN" calibrate --track "$OUT/husky.csv" --method online-pose 2>&1 || true
} > "$OUT/calibrate.txt"
python3 - "$OUT/husky.csv" "$OUT/husky-wheels.csv" "$R_N" "$D_N" <<'PY'
import csv, sys
src, dst, r_n, d_n = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4])
lines = open(src).read().splitlines()
meta = [l for l in lines if l.startswith("#")]
rows = list(csv.reader(l for l in lines if not l.startswith("#")))
iv, iw = rows[0].index("v_cmd"), rows[0].index("w_cmd")
out = [rows[0] + ["omega_l", "omega_r"]]
for r in rows[1:]:
    if r[iv] == "" or r[iw] == "":
        out.append(r + ["", ""])
        continue
    v, w = float(r[iv]), float(r[iw])
    out.append(r + [repr((v - w * d_n / 2) / r_n), repr((v + w * d_n / 2) / r_n)])
meta += [f"# robot.wheel_radius_left: {r_n}", f"# robot.wheel_radius_right: {r_n}", f"# robot.wheel_base: {d_n}"]
with open(dst, "w") as f:
    f.write("\n".join(meta) + "\n")
    csv.writer(f, lineterminator="\n").writerows(out)
PY
for memory in default 200 1000; do
  extra=()
  [ "$memory" != default ] && extra=(--pose-memory-m "$memory")
  echo "== online-pose from the twist as wheel rates (R_n $R_N m, D_n $D_N m), memory $memory" >> "$OUT/calibrate.txt"
  "$BIN" calibrate --track "$OUT/husky-wheels.csv" --method online-pose "${extra[@]}" >> "$OUT/calibrate.txt"
done
cat "$OUT/calibrate.txt"
