"""Copies a track (odotune-track/1) without its ground-truth columns (gt_*),
so that a fit can only use the track's position fixes.

    python3 reproduce/strip_ground_truth.py IN.csv OUT.csv
"""
import csv
import sys

lines = open(sys.argv[1]).read().splitlines()
rows = list(csv.reader(l for l in lines if not l.startswith("#")))
keep = [i for i, h in enumerate(rows[0]) if not h.startswith("gt_")]
with open(sys.argv[2], "w") as f:
    f.write("".join(l + "\n" for l in lines if l.startswith("#")))
    csv.writer(f, lineterminator="\n").writerows([[r[i] for i in keep] for r in rows])
