#!/usr/bin/env bash
# The tune of reproduce/rl-ground-truth.sh on other draws of the fixes' noise
# (docs/robot-localization.md, "Other fix seeds"): OptiOdom and Lost in the
# Woods (the cheap datasets; MRCLAM's tunes take 15 min each), fixes from
# `odotune fixes` seeds FIX_SEEDS (default 1 2 3), each tuned with the plain
# fitness and with --subtract-fix-variance, PSO seeds 1-3, judged on the
# held-out recordings against ground truth. The folds only (no calibration).
# Writes OUT/fixF-plain/ and OUT/fixF-subtract/ (each as rl-ground-truth.sh's
# OUT) and OUT/table.md; resumes where it stopped.
#   bash reproduce/rl-fix-seeds.sh [OUT_DIR]   (default out/rl-fix-seeds)
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-out/rl-fix-seeds}
FIX_SEEDS=${FIX_SEEDS:-"1 2 3"}
mkdir -p "$OUT"
start=$SECONDS
for f in $FIX_SEEDS; do
  for mode in plain subtract; do
    extra=""
    [ "$mode" = subtract ] && extra=--subtract-fix-variance
    dir=$OUT/fix$f-$mode
    # The same tracks and fixes for both fitnesses.
    if [ "$mode" = subtract ] && [ ! -f "$dir/tracks/done" ]; then
      mkdir -p "$dir"
      cp -r "$OUT/fix$f-plain/tracks" "$dir/"
    fi
    FIX_SEED=$f TUNE_EXTRA="$extra" FOLDS_ONLY=1 DATASETS="optiodom litw" \
      bash reproduce/rl-ground-truth.sh "$dir" > "$dir.log"
    echo "fix seed $f, $mode: done"
  done
done
python3 reproduce/rl-fix-seeds-table.py "$OUT" "$FIX_SEEDS" | tee "$OUT/table.md"
echo "wall $((SECONDS - start)) s"
