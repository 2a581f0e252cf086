#!/usr/bin/env bash
# When a tune cannot help (docs/robot-localization.md): a simulated
# wheelchair (scenarios/wheelchair.yaml, with a gyro) with a known effect
# left out of its model, tuned without ground truth and judged against it on
# another seed's drive:
#   gyro_bias b = 0.02 rad/s  the user's file fuses the gyro's yaw rate; then
#                             the bias `odotune diagnose` finds, subtracted
#                             from gyro_z (as a driver's offset would), and the
#                             tune again;
#   longitudinal_slip k = 0.3 s²/m  against the same robot without slip.
# 1 Hz fixes, σ 0.1 m. Writes OUT/sim/ and OUT/sim/table.md. Run by rl-ground-truth.sh.
#   bash reproduce/rl-physics-sim.sh [OUT_DIR]   (default out/rl-ground-truth)
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-out/rl-ground-truth}
BIN=${BIN:-build/odotune}
D=$OUT/sim
mkdir -p "$D"
cat > "$D/user.yaml" << 'YAML'
# robot_localization's ekf_node as a team sets it up for this robot: two_d_mode,
# the wheel odometry's velocities, the gyro's yaw rate, the fixes as x, y;
# robot_localization's default noise. initial_state: the first fix (the replay).
ekf_filter_node:
  ros__parameters:
    frequency: 30.0
    two_d_mode: true
    # odom0: the drive controller's odometry; its twist covariance is
    # diff_drive_controller's twist_covariance_diagonal [0.001, 0.001, 0.001, 1e6, 1e6, 0.03].
    odom0: odom
    odom0_config: [false, false, false, false, false, false, true, true, false, false, false, true, false, false, false]
    # imu0: the gyro's yaw rate, (0.02 deg/s)^2 as the phidgets_spatial driver publishes it.
    imu0: imu/data
    imu0_config: [false, false, false, false, false, false, false, false, false, false, false, true, false, false, false]
    # odom1: the position fixes, x and y with their own variances.
    odom1: odometry/fixes
    odom1_config: [true, true, false, false, false, false, false, false, false, false, false, false, false, false, false]
YAML

# make NAME SEED [--effect ...]: the drive and its fixes.
make() {
  local name=$1 seed=$2
  shift 2
  "$BIN" simulate scenarios/wheelchair.yaml -o "$D/$name-$seed.raw.csv" --seed "$seed" "$@" > /dev/null
  "$BIN" fixes "$D/$name-$seed.raw.csv" -o "$D/$name-$seed.csv" --rate-hz 1 --sigma-m 0.1 --seed "$seed" > /dev/null
}
for seed in 1 2; do
  make clean $seed
  make bias $seed --effect gyro_bias:b=0.02
  make slip $seed --effect longitudinal_slip:k=0.3
done
"$BIN" diagnose "$D/bias-1.csv" --heldout "$D/bias-2.csv" --json "$D/diagnose-bias.json" > "$D/diagnose-bias.txt"
"$BIN" diagnose "$D/slip-1.csv" --heldout "$D/slip-2.csv" --json "$D/diagnose-slip.json" > "$D/diagnose-slip.txt"
b=$(python3 -c "
import json, sys
d = json.load(open('$D/diagnose-bias.json'))
print(next(f['params']['b'] for f in d['findings'] if f['effect'] == 'gyro_bias'))")
for seed in 1 2; do  # the diagnosed bias subtracted from the gyro
  python3 - "$D/bias-$seed.csv" "$D/corrected-$seed.csv" "$b" << 'PY'
import csv, sys
lines = open(sys.argv[1]).read().splitlines()
head = [l for l in lines if l.startswith("#")]
rows = list(csv.reader(l for l in lines if not l.startswith("#")))
k = rows[0].index("gyro_z")
for r in rows[1:]:
    if r[k]:
        r[k] = repr(float(r[k]) - float(sys.argv[3]))
with open(sys.argv[2], "w") as f:
    f.write("".join(l + "\n" for l in head) + f"# gyro_z corrected: {sys.argv[3]} rad/s subtracted (odotune diagnose)\n")
    csv.writer(f, lineterminator="\n").writerows(rows)
PY
done
echo "| robot | user file: fixes fused | tuned: fixes fused | user file: outages | tuned: outages |" > "$D/table.md"
echo "|---|---:|---:|---:|---:|" >> "$D/table.md"
for k in clean bias corrected slip; do
  "$BIN" tune --rl-params "$D/user.yaml" --track "$D/$k-1.csv" --outage-every 10 --no-input-covariances \
    --config-out "$D/tuned-$k.yaml" > "$D/tune-$k.txt"
  for f in user "tuned-$k"; do
    "$BIN" eval --rl-params "$D/$f.yaml" --track "$D/$k-2.csv" --outage-every 10 --json "$D/$f-on-$k.json" > /dev/null
  done
  python3 - "$D" "$k" >> "$D/table.md" << 'PY'
import json, sys
d, k = sys.argv[1:3]
u = json.load(open(f"{d}/user-on-{k}.json"))["truth"]
t = json.load(open(f"{d}/tuned-{k}-on-{k}.json"))["truth"]
print(f"| {k} | {u['run']['rmse_m']:.3f} | {t['run']['rmse_m']:.3f} | {u['outages']['rmse_m']:.3f} | {t['outages']['rmse_m']:.3f} |")
PY
done
echo "diagnosed gyro bias: $b rad/s" >> "$D/table.md"
cat "$D/table.md"
