#!/usr/bin/env bash
# One recording as two: cuts an odotune track at the middle of its data rows'
# time span into DIR/NAME-first-half.csv and DIR/NAME-second-half.csv
# (metadata kept, "-first-half"/"-second-half" appended to the name); prints
# the middle time. Shared by diagnose-track-halves.sh and learned-real.sh.
#   bash reproduce/track-halves.sh TRACK.csv DIR NAME
set -euo pipefail
in=$1 dir=$2 name=$3
mkdir -p "$dir"
read -r t0 t1 < <(awk -F, '!/^#/ && $1 ~ /^[0-9.]+$/ {if (!n++) a = $1; b = $1} END {print a, b}' "$in")
mid=$(echo "$t0 $t1" | awk '{print ($1 + $2) / 2}')
for half in first second; do
  awk -F, -v mid="$mid" -v half=$half '
    /^# name:/ {print $0 "-" half "-half"; next}
    /^#/ || $1 !~ /^[0-9.]+$/ {print; next}
    (half == "first" && $1 < mid) || (half == "second" && $1 >= mid) {print}' "$in" > "$dir/$name-$half-half.csv"
done
echo "$mid"
