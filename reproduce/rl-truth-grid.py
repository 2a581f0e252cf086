#!/usr/bin/env python3
"""A ground-truth check of a robot_localization file on one recording (docs/robot-localization.md):
the file's process noise with its position (x, y) and velocity (vx, vy, vyaw) entries scaled by a
grid of factors, each replayed with `eval --noise-from` and scored by the track's ground truth
(whole run with every fix fused). Prints the five best settings and the file's own. Not a tune: it
uses the ground truth of the recording it scores, to see how far from the best a tuned file is.

   python3 reproduce/rl-truth-grid.py USER.yaml TRACK.csv [BIN] [OUT_DIR]
"""
import itertools
import json
import subprocess
import sys
from pathlib import Path

user, track = sys.argv[1], sys.argv[2]
binary = sys.argv[3] if len(sys.argv) > 3 else "build/odotune"
out = Path(sys.argv[4] if len(sys.argv) > 4 else "out/rl-truth-grid")
out.mkdir(parents=True, exist_ok=True)
# robot_localization's default process_noise_covariance diagonal (its params/ekf.yaml).
BASE = [0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015]
res = []
for fp, fv in itertools.product([1e-4, 1e-3, 1e-2, 1e-1, 1, 10], [1e-2, 1e-1, 1, 10]):
    q = list(BASE)
    for i in (0, 1):
        q[i] *= fp
    for i in (6, 7, 11):
        q[i] *= fv
    flat = [q[i] if i == j else 0.0 for i in range(15) for j in range(15)]
    noise = out / f"q-{fp:g}-{fv:g}.yaml"
    noise.write_text("ekf_filter_node:\n  ros__parameters:\n    process_noise_covariance: ["
                     + ", ".join(repr(x) for x in flat) + "]\n")
    js = out / f"eval-{fp:g}-{fv:g}.json"
    subprocess.run([binary, "eval", "--rl-params", user, "--track", track, "--noise-from", str(noise),
                    "--outage-every", "30", "--json", str(js)], check=True, capture_output=True)
    t = json.loads(js.read_text())["tracks"][0]["truth"]
    res.append((t["run"]["rmse_m"], t["outages"]["rmse_m"], fp, fv))
res.sort()
print("| position factor | velocity factor | fixes fused [m] | outages [m] |")
print("|---:|---:|---:|---:|")
for run, outages, fp, fv in res[:5] + [r for r in res if r[2] == 1 and r[3] == 1]:
    print(f"| {fp:g} | {fv:g} | {run:.3f} | {outages:.3f} |")
