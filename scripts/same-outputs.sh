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
#   grid/rows.txt         every row of the grid's store but its wall time, by key
#   grid/export-*.yaml    odotune export of that store (both formats)
#   diagnosis-json/       odotune diagnose on an OptiOdom run and the pooled
#                         OptiOdom runs: JSON, scenario and controller files
#   husky/                the Husky's robot_localization tune (reproduce/husky-rl.sh):
#                         the written files, JSON and trajectories
# Timing columns and keys (seconds a step took, ms per iteration), the
# output folder's path and the experiment's hash are masked, so that `diff -r`
# of two folders shows only real changes. Takes about 6 minutes on 2 cores.
set -euo pipefail
if [[ $# -ne 2 ]]; then
  sed -n '2,25p' "$0" | sed 's/^# \{0,1\}//'
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
python3 - "$out/grid/study.sqlite" > "$out/grid/rows.txt" <<'PY'
import sqlite3, sys
db = sqlite3.connect(sys.argv[1])
cols = [c[1] for c in db.execute("PRAGMA table_info(runs)") if c[1] not in ("id", "seconds")]
for row in db.execute(f"SELECT {', '.join(cols)} FROM runs ORDER BY key"):
    print(" | ".join(f"{c}={v!r}" for c, v in zip(cols, row)))
PY
"$bin" export "$out/grid/study.sqlite" --select model=gyro,track=track3,mode=7 --format robot_localization \
  --out "$out/grid/export-rl.yaml" > /dev/null
"$bin" export "$out/grid/study.sqlite" --select model=rq,track=track1,mode=1 --format odotune \
  --out "$out/grid/export-odotune.yaml" > /dev/null
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
mkdir -p "$out/diagnosis-json"
OO=../shared/data/real/optiodom_diff
for r in free/030120210001/030120210001_run-01 circular/231220200146/231220200146_run-01 \
         free/030120210001/030120210001_run-02; do
  "$bin" import optiodom "$OO/$r.csv" -o "$out/diagnosis-json/$(basename "$r").csv" > /dev/null
done
D=$out/diagnosis-json
"$bin" diagnose "$D/030120210001_run-01.csv" --json "$D/run-01.json" --scenario-out "$D/run-01-scenario.yaml" \
  --controller-out "$D/run-01-controller.yaml" --controller ros2_control > "$D/run-01.txt" 2>&1 || true
"$bin" diagnose "$D/030120210001_run-01.csv" "$D/231220200146_run-01.csv" --heldout "$D/030120210001_run-02.csv" \
  --json "$D/pooled.json" > "$D/pooled.txt" 2>&1
rm -f "$D"/*.csv
BIN="$bin" bash "$root/reproduce/husky-rl.sh" "$out/husky" > /dev/null 2>&1
rm -f "$out/husky"/*.png
# What differs from run to run or with the output folder is masked: timing
# columns, JSON keys and lines; the folder's path (OUT); the experiment's hash
# (its store path is part of it).
python3 - "$out" <<'PY'
import csv, json, pathlib, re, sys
out = sys.argv[1]
timing = {"simulate_s", "truth_s", "diagnose_s", "calibration_wall_s"}
def drop_timing(v):
    if isinstance(v, dict):
        return {k: drop_timing(x) for k, x in v.items() if k not in ("seconds", "timing_s")}
    return [drop_timing(x) for x in v] if isinstance(v, list) else v
for f in pathlib.Path(out).rglob("*"):
    if f.suffix not in (".json", ".txt", ".yaml", ".md", ".tum"):
        continue
    text = f.read_text().replace(out, "OUT")
    text = re.sub(r"(experiment [^,()]*, )[0-9a-f]{16}", r"\1HASH", text)
    text = re.sub(r"evaluations in [0-9.]+ s", "evaluations in T s", text)
    if f.suffix == ".json":
        text = json.dumps(drop_timing(json.loads(text)), indent=1, sort_keys=True) + "\n"
    f.write_text(text)
for f in pathlib.Path(out).rglob("*.csv"):
    rows = list(csv.reader(f.open()))
    keep = [i for i, h in enumerate(rows[0]) if h not in timing and not h.startswith("ms_per_iter")]
    with f.open("w", newline="") as o:
        csv.writer(o, lineterminator="\n").writerows([[r[i] for i in keep if i < len(r)] for r in rows])
PY
echo "same-outputs.sh: wrote $out"
