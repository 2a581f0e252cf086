#!/usr/bin/env python3
"""The tables of reproduce/rl-ground-truth.sh (docs/robot-localization.md reads them).

   python3 reproduce/rl-ground-truth-tables.py OUT "1 2 3" "0.1 1" [FIX_SEED [TUNE_EXTRA]]
"""
import json
import statistics
import sys
from pathlib import Path

out = Path(sys.argv[1])
seeds = sys.argv[2].split()
sigmas = sys.argv[3].split()
fix_seed = sys.argv[4] if len(sys.argv) > 4 else "1"
tune_extra = sys.argv[5] if len(sys.argv) > 5 else ""
FOLDS = {
    "optiodom": ["tune-dec23", "tune-jan"],
    "mrclam": ["tune-12", "tune-13", "tune-23"],
    "litw": ["tune-first"],
}
NAMES = {"optiodom": "OptiOdom", "mrclam": "MRCLAM", "litw": "Lost in the Woods"}


def load(p):
    with open(p) as f:
        return json.load(f)["tracks"][0]


def held_out(dataset, fold, sigma):
    d = out / dataset / fold / f"s{sigma}"
    rows = []
    for user in sorted(d.glob("user-*.json")):
        rec = user.stem[len("user-"):]
        u = load(user)
        s = [load(d / f"seed{k}-{rec}.json") for k in seeds]
        rows.append((rec, u, s))
    return rows


def rmse(r, *keys):
    v = r
    for k in keys:
        v = v[k]
    return v["rmse_m"]


def tune_text(dataset, fold, sigma):
    t = (out / dataset / fold / f"s{sigma}" / "tune.txt").read_text()
    wall = [l for l in t.splitlines() if l.startswith("wall")]
    return wall[0].split()[1] if wall else "?"


print("# robot_localization on held-out recordings, against ground truth\n")
print(f"PSO seeds {', '.join(seeds)}; fixes at 1 Hz (odotune fixes, seed {fix_seed})"
      + (f"; tuned with {tune_extra}" if tune_extra else "") + ". Ratio: tuned / user file.\n")
summary = []
for dataset, folds in FOLDS.items():
    for sigma in sigmas:
        print(f"## {NAMES[dataset]}, fixes σ {sigma} m\n")
        print("| tuned on | held out | user: fixes fused | tuned (seeds) | ratio (seeds) | user: outages | "
              "tuned outages (seeds) | user: held-out fixes | tuned held-out fixes (seeds) |")
        print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
        ratios, out_ratios, fix_ratios, users, tuned_by_seed = [], [], [], [], [[] for _ in seeds]
        for fold in folds:
            rows = held_out(dataset, fold, sigma)
            for rec, u, s in rows:
                ur, uo, uf = rmse(u, "truth", "run"), rmse(u, "truth", "outages"), rmse(u, "fixes", "heldout")
                tr = [rmse(x, "truth", "run") for x in s]
                to = [rmse(x, "truth", "outages") for x in s]
                tf = [rmse(x, "fixes", "heldout") for x in s]
                ratios += [x / ur for x in tr]
                users.append(ur)
                for k, x in enumerate(tr):
                    tuned_by_seed[k].append(x)
                out_ratios += [x / uo for x in to if uo]
                fix_ratios += [x / uf for x in tf]
                fmt = lambda v: "/".join(f"{x:.3f}" for x in v)
                print(f"| {fold} ({tune_text(dataset, fold, sigma)} s) | {rec} | {ur:.3f} | {fmt(tr)} | "
                      f"{'/'.join(f'{x / ur:.2f}' for x in tr)} | {uo:.3f} | {fmt(to)} | {uf:.3f} | {fmt(tf)} |")
        print()
        if ratios:
            summary.append((NAMES[dataset], sigma, max(ratios), statistics.mean(ratios),
                            statistics.mean(out_ratios) if out_ratios else float("nan"),
                            statistics.mean(fix_ratios), len(users), statistics.mean(users),
                            [statistics.mean(t) for t in tuned_by_seed]))

def setups(dataset, fold, sigma):
    """Per held-out recording: whole-run and outage RMSE of the four set-ups (seeds averaged)."""
    base = out / dataset / fold / f"s{sigma}"
    cal = base / "calibrated"
    rows = []
    for rec, u, s in held_out(dataset, fold, sigma):
        if not (cal / f"user-{rec}.json").exists():
            continue
        c = load(cal / f"user-{rec}.json")
        ct = [load(cal / f"seed{k}-{rec}.json") for k in seeds]
        row = {}
        for key in ("run", "outages"):
            row[key] = (rmse(u, "truth", key), statistics.mean(rmse(x, "truth", key) for x in s),
                        rmse(c, "truth", key), statistics.mean(rmse(x, "truth", key) for x in ct),
                        max(rmse(x, "truth", key) for x in ct))
        rows.append((rec, row))
    return rows


print("## Calibrate, then tune: the four set-ups on the held-out recordings\n")
print("Whole-run RMSE with the fixes fused / through the simulated fix outages [m]; tuned set-ups: the mean "
      "over the seeds. Calibration from the fitted recordings' fixes (their ground truth removed).\n")
print("| dataset | σ [m] | held out | user file | tune alone | calibration alone | calibrate, then tune |")
print("|---|---:|---|---:|---:|---:|---:|")
cal_summary = []
for dataset, folds in FOLDS.items():
    for sigma in sigmas:
        acc = []
        for fold in folds:
            for rec, row in setups(dataset, fold, sigma):
                r, o = row["run"], row["outages"]
                acc.append(row)
                print(f"| {NAMES[dataset]} | {sigma} | {rec} ({fold}) | {r[0]:.3f} / {o[0]:.3f} | "
                      f"{r[1]:.3f} / {o[1]:.3f} | {r[2]:.3f} / {o[2]:.3f} | {r[3]:.3f} / {o[3]:.3f} |")
        if acc:
            mean = lambda key, i: statistics.mean(a[key][i] for a in acc)
            cal_summary.append((NAMES[dataset], sigma, [mean("run", i) for i in range(4)],
                                [mean("outages", i) for i in range(4)]))
print()
refused = sorted(out.glob("*/*/s*/calibrated/calibration-refused.txt"))
if refused:
    print("Calibrations `calibrate` refused (no calibrated set-ups for these folds):\n")
    for p in refused:
        sigma, fold, dataset = p.parts[-3][1:], p.parts[-4], p.parts[-5]
        print(f"- {NAMES[dataset]}, {fold}, σ {sigma} m: `{p.read_text().strip()}`")
    print()
if cal_summary:
    print("Means over the held-out recordings (whole run / outages) [m]:\n")
    print("| dataset | σ [m] | user file | tune alone | calibration alone | calibrate, then tune |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, sigma, r, o in cal_summary:
        print(f"| {name} | {sigma} | " + " | ".join(f"{a:.3f} / {b:.3f}" for a, b in zip(r, o)) + " |")
    print()

print("## Summary: tuned / user file over every held-out recording and seed\n")
print("Ratios: worst and mean over recordings and seeds. RMSE [m]: the mean over the held-out recordings.\n")
print("| dataset | fixes σ [m] | held out | user file, fixes fused | tuned (seeds) | worst ratio, fixes fused | "
      "mean ratio, fixes fused | mean ratio, outages | mean ratio, held-out fixes |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
for name, sigma, worst, mean, mo, mf, n, u, t in summary:
    print(f"| {name} | {sigma} | {n} | {u:.3f} | {'/'.join(f'{x:.3f}' for x in t)} | {worst:.3f} | {mean:.3f} | "
          f"{mo:.3f} | {mf:.3f} |")
