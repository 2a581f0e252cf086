#!/usr/bin/env bash
# Cuts an odotune track at the middle of its data rows' time span into two
# recordings, PREFIX-first-half.csv and PREFIX-second-half.csv (metadata kept,
# "-first-half"/"-second-half" appended to the name): one drive as two
# recordings for `odotune diagnose FIRST --heldout SECOND`.
#   bash scripts/split-track-halves.sh TRACK.csv PREFIX
set -euo pipefail
in=$1 prefix=$2
# The first and the last data row's time; rows split at their middle.
read -r t0 t1 < <(awk -F, '!/^#/ && $1 ~ /^[0-9.]+$/ {if (!n++) a = $1; b = $1} END {print a, b}' "$in")
mid=$(echo "$t0 $t1" | awk '{print ($1 + $2) / 2}')
for half in first second; do
  awk -F, -v mid="$mid" -v half=$half '
    /^# name:/ {print $0 "-" half "-half"; next}
    /^#/ || $1 !~ /^[0-9.]+$/ {print; next}
    (half == "first" && $1 < mid) || (half == "second" && $1 >= mid) {print}' "$in" > "$prefix-$half-half.csv"
done
