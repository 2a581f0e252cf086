#!/usr/bin/env python3
"""The table of reproduce/rl-fix-seeds.sh: per dataset, fixes' σ and fix seed,
the tuned / user file ratios of each fitness on the held-out recordings, read
from the summary rows of each run's tables.md (rl-ground-truth-tables.py).

   python3 reproduce/rl-fix-seeds-table.py OUT "1 2 3"
"""
import statistics
import sys
from pathlib import Path

out = Path(sys.argv[1])
fix_seeds = sys.argv[2].split()
MODES = ("plain", "subtract")


def summary(path):
    """{(dataset, sigma): (worst, mean, mean outages)} of a tables.md."""
    if not path.exists():
        sys.exit(f"{path}: missing (run reproduce/rl-fix-seeds.sh first)")
    rows, inside = {}, False
    for line in path.read_text().splitlines():
        if line.startswith("## Summary"):
            inside = True
        elif inside and rows and not line.startswith("|"):
            break  # the summary table has ended; later tables have other columns
        elif inside and line.startswith("| ") and not line.startswith("| dataset"):
            c = [x.strip() for x in line.strip("|").split("|")]
            rows[(c[0], c[1])] = (float(c[5]), float(c[6]), float(c[7]))
    if not rows:
        sys.exit(f"{path}: no summary rows (expected a '## Summary' table of rl-ground-truth-tables.py)")
    return rows


runs = {(f, m): summary(out / f"fix{f}-{m}" / "tables.md") for f in fix_seeds for m in MODES}
keys = sorted({k for r in runs.values() for k in r}, key=lambda k: (k[0], float(k[1])))
print("# The tune on other draws of the fixes' noise\n")
print("Whole-run RMSE against ground truth on the held-out recordings, tuned / user file: worst and mean "
      "over the recordings and PSO seeds 1-3; outages: the mean ratio through the simulated outages.\n")
print("| dataset | fixes σ [m] | fix seed | plain: worst | plain: mean | plain: outages | "
      "variance taken out: worst | variance taken out: mean | variance taken out: outages |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
for k in keys:
    per = {m: [runs[(f, m)][k] for f in fix_seeds if k in runs[(f, m)]] for m in MODES}
    for f in fix_seeds:
        cells = []
        for m in MODES:
            r = runs[(f, m)].get(k)
            cells += [f"{r[0]:.2f}", f"{r[1]:.2f}", f"{r[2]:.2f}"] if r else ["", "", ""]
        print(f"| {k[0]} | {k[1]} | {f} | " + " | ".join(cells) + " |")
    cells = []
    for m in MODES:
        v = per[m]
        cells += ([f"**{max(x[0] for x in v):.2f}**", f"**{statistics.mean(x[1] for x in v):.2f}**",
                   f"**{statistics.mean(x[2] for x in v):.2f}**"] if v else ["", "", ""])
    print(f"| {k[0]} | {k[1]} | all | " + " | ".join(cells) + " |")
