#!/usr/bin/env bash
# same-outputs.sh: regenerates the outputs a refactoring must leave unchanged,
# with one odotune binary, into a folder; run it with the old and the new
# binary and compare the folders (`diff -r`).
#
#   bash scripts/same-outputs.sh BIN OUT_DIR
#
# What it writes (each from a command the docs give, some reduced in size):
#   demo.txt              odotune demo, without its timing line
#   grid/table1.csv …     the study's experiment (experiments/study.yaml) with one
#                         seed instead of twenty, leave-one-out included, then
#                         odotune report's Table 1 and generalisation table
#   resampling/*.csv      odotune study resampling (Table I and its runs)
#   calibration/*.csv     odotune study calibration (Table II and its runs)
#   diagnosis/cases.csv   odotune study diagnosis on the docs seed's first 30 cases
#   calibration-real/     the real-data calibration (reproduce script), heldout.csv
# Timing columns (seconds a step took, ms per iteration) are removed. Takes
# about 15 minutes on 2 cores.
set -euo pipefail
if [[ $# -ne 2 ]]; then
  sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
fi
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
mkdir -p "$2"
out="$(cd "$2" && pwd)"
cd "$root"

"$bin" demo | grep -v ' s of optimisation in all' > "$out/demo.txt"

mkdir -p "$out/grid"
sed -e 's|^seeds:.*|seeds: [1]|' -e "s|^store:.*|store: $out/grid/study.sqlite|" \
    -e "s|^tracks:.*|tracks: [$root/data/tracks/track*.csv]|" experiments/study.yaml > "$out/grid/study.yaml"
"$bin" grid "$out/grid/study.yaml" > /dev/null
"$bin" report "$out/grid/study.sqlite" --out "$out/grid/report" > /dev/null
cp "$out/grid/report/table1.csv" "$out/grid/report/generalisation.md" "$out/grid/"
rm -rf "$out/grid/report" "$out/grid/study.sqlite"* "$out/grid/study.yaml"

"$bin" study resampling --out "$out/resampling-all" > /dev/null
"$bin" study calibration --out "$out/calibration-all" > /dev/null
for d in resampling calibration; do
  mkdir -p "$out/$d"
  cp "$out/$d-all"/*.csv "$out/$d/"
  rm -rf "$out/$d-all"
done

"$bin" study diagnosis --cases 30 --seed 20261128 --out "$out/diagnosis-all" > /dev/null 2>&1
mkdir -p "$out/diagnosis"
cp "$out/diagnosis-all/cases.csv" "$out/diagnosis/"
rm -rf "$out/diagnosis-all"

BIN="$bin" bash "$root/reproduce/calibrate-real.sh" "$out/calibration-real-all" > /dev/null
mkdir -p "$out/calibration-real"
cp "$out/calibration-real-all/heldout.csv" "$out/calibration-real/"
rm -rf "$out/calibration-real-all"
# Timing columns are the ones that differ from run to run: drop them.
python3 - "$out" <<'PY'
import csv, pathlib, sys
timing = {"simulate_s", "truth_s", "diagnose_s", "calibration_wall_s"}
for f in pathlib.Path(sys.argv[1]).rglob("*.csv"):
    rows = list(csv.reader(f.open()))
    keep = [i for i, h in enumerate(rows[0]) if h not in timing and not h.startswith("ms_per_iter")]
    with f.open("w", newline="") as o:
        csv.writer(o, lineterminator="\n").writerows([[r[i] for i in keep if i < len(r)] for r in rows])
PY
echo "same-outputs.sh: wrote $out"
