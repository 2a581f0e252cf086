#!/usr/bin/env bash
# The Husky's file (husky_ekf.yaml) run as robot_localization's ukf_node
# (--filter ukf) beside its ekf_node (docs/robot-localization-ukf.md): the
# untuned file of each and the tune of docs/husky.md's design (a grid of
# -2, 0, 2 decades on the diagonal, a profile, no seeded refinement) scored by
# held-out fixes alone, on each half, each judged on the other half by both
# held-out protocols (every 5th fix; 30- and 60-s GPS outages). The UKF's own
# file diverges through the outages, so its tune cannot score them; the EKF's
# is tuned the same way, so the two compare like for like. Writes OUT/.
#   bash reproduce/husky-ukf.sh [OUT_DIR]   (default out/husky-ukf)
# Needs build/odotune. BIN and REAL as in reproduce/husky-rl.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
REAL=${REAL:-../shared/data/real}
OUT=${1:-out/husky-ukf}
BIN=${BIN:-build/odotune}
BAGS=$REAL/robot_localization_bags
TF=imu_link=0,-0.3,0.52,1.5707963267948966,0,-1.5707963267948966
MID=197.65
SRC=(--bag "$BAGS/test1.bag" --tf "$TF" --gps-heading-fit 60)
# shellcheck disable=SC2054 # the commas are inside flag values
TUNE=(--fitness heldout-fixes --space diagonal --no-input-covariances --outage "30,60" --outage-every 10
      --grid=-2,0,2 --refine 0 --seed 1)
mkdir -p "$OUT"
start=$SECONDS
for filter in ekf ukf; do
  for fold in first second; do
    if [ $fold = first ]; then
      span=(--until "$MID") judge=(--from "$MID")
    else
      # judged as the tune judges it: the GPS fused for the first 60 s, then an outage to the midpoint
      span=(--from "$MID") judge=(--from 60 --until "$MID")
    fi
    dir=$OUT/$filter-$fold
    mkdir -p "$dir"
    "$BIN" eval --rl-params "$BAGS/husky_ekf.yaml" --filter $filter "${SRC[@]}" "${judge[@]}" \
      > "$dir/user-eval.txt"
    if ! grep -q '^wall' "$dir/tune.txt" 2> /dev/null; then
      t0=$SECONDS
      "$BIN" tune --rl-params "$BAGS/husky_ekf.yaml" --filter $filter "${SRC[@]}" "${span[@]}" "${TUNE[@]}" \
        --config-out "$dir/tuned.yaml" > "$dir/tune.txt"
      echo "wall $((SECONDS - t0)) s" >> "$dir/tune.txt"
    fi
    "$BIN" eval --rl-params "$dir/tuned.yaml" "${SRC[@]}" "${judge[@]}" > "$dir/tuned-eval.txt"
    echo "$filter, tuned on the $fold half: done" >&2
  done
done
python3 - "$OUT" <<'PY' | tee "$OUT/table.md"
import re, sys
out = sys.argv[1]
NUM = r"(diverged|[0-9.]+)"
def judged(d):
    """The tune's judged figures (user file -> tuned) and the written file's outage replayed by eval."""
    t = open(f"{d}/tune.txt").read()
    o = re.search(r"GPS outage:\s+" + NUM + r"\s+->\s+" + NUM, t)
    f = re.search(r"every 5th fix held out:\s+" + NUM + r"\s+->\s+" + NUM, t)
    e = re.search(r"GPS outage RMSE\s+" + NUM, open(f"{d}/tuned-eval.txt").read())
    wall = re.search(r"^wall (\d+)", t, re.M).group(1)
    return o.group(1), o.group(2), f.group(1), f.group(2), e.group(1), wall
print("| filter | tuned on → judged on | outage: user file | outage: tuned | every 5th fix: user file | "
      "every 5th fix: tuned | tuned file replayed by eval: outage | tune wall [s] |")
print("|---|---|---:|---:|---:|---:|---:|---:|")
for f in ("ekf", "ukf"):
    for fold, other in (("first", "second"), ("second", "first")):
        uo, to, uf, tf, replayed, wall = judged(f"{out}/{f}-{fold}")
        print(f"| {f.upper()} | {fold} half → {other} | {uo} | {to} | {uf} | {tf} | {replayed} | {wall} |")
PY
echo "wall $((SECONDS - start)) s"
