#!/usr/bin/env python3
"""How the robot_localization tune's design was chosen, on the first half of
the Husky drive alone (t < 197.65 s; the second half is the held-out data of
docs/husky.md and is never read here).

Each design (a set of `odotune tune --rl-params` flags) tunes on the first T
seconds and is judged on T … 197.65 s, for T = 100, 120, 140, against
robot_localization's defaults (ratios tuned / defaults):
  windows  simulated GPS outages of 30 and 60 s starting every 5 s from T
           (`odotune eval --outages 30,60 --outage-every 5 --from T`), the GPS
           fused before each: many outages, so one path's luck weighs little;
  fifth    every 5th fix of the judged span held out;
  outage   one outage from T to 197.65 s (shown, not scored: one sample).
A design is scored by the mean over T of windows + fifth.

  python3 reproduce/husky-rl-design.py [OUT_DIR] [DESIGN ...]   (default out/husky-rl-design, all designs)
Needs build/odotune. REAL as in reproduce/husky-rl.sh.
"""
import json
import os
import subprocess
import sys

REAL = os.environ.get("REAL", "../shared/data/real")
BIN = os.environ.get("BIN", "build/odotune")
BAGS = f"{REAL}/robot_localization_bags"
TF = "imu_link=0,-0.3,0.52,1.5707963267948966,0,-1.5707963267948966"
PARAMS = f"{BAGS}/husky_ekf.yaml"
BAG = ["--bag", f"{BAGS}/test1.bag", "--tf", TF, "--gps-heading-fit", "60"]
SPLITS = [100.0, 120.0, 140.0]
MID = 197.65

DESIGNS = {
    # The tune as it was: PSO over the whole box, outages one after another
    # (one every 1.5 lengths), held-out fixes may get worse.
    "old": ["--fitness", "both", "--grid", "none", "--refine", "10", "--outage", "30", "--outage-every", "45",
            "--allow-worse-heldout", "--particles", "30", "--iterations", "40"],
    "grid": ["--fitness", "both", "--refine", "0", "--outage", "30"],
    "grid-60": ["--fitness", "both", "--refine", "0", "--outage", "30,60"],
    "grid-outage": ["--fitness", "outage", "--refine", "0", "--outage", "30"],
    "grid-refine": ["--fitness", "both", "--refine", "1", "--outage", "30", "--particles", "20",
                    "--iterations", "30"],
    "grid-refine-half": ["--fitness", "both", "--refine", "0.5", "--outage", "30", "--particles", "20",
                         "--iterations", "30"],
    "grid-refine-blocks": ["--fitness", "both", "--space", "blocks", "--refine", "1", "--outage", "30",
                           "--particles", "20", "--iterations", "30"],
    "grid-refine-prior": ["--fitness", "both", "--refine", "1", "--prior", "0.05", "--outage", "30",
                          "--particles", "20", "--iterations", "30"],
    "grid-refine-blocks-seed2": ["--fitness", "both", "--space", "blocks", "--refine", "1", "--outage", "30",
                                 "--particles", "20", "--iterations", "30", "--seed", "2"],
    "grid-refine-blocks-seed3": ["--fitness", "both", "--space", "blocks", "--refine", "1", "--outage", "30",
                                 "--particles", "20", "--iterations", "30", "--seed", "3"],
    "grid5": ["--fitness", "both", "--refine", "0", "--outage", "30", "--grid=-2,-1,0,1,2"],
    "grid-refine-determined": ["--fitness", "both", "--refine", "1", "--outage", "30", "--particles", "12",
                               "--iterations", "20"],
    "grid-refine-determined-seed2": ["--fitness", "both", "--refine", "1", "--outage", "30", "--particles",
                                     "12", "--iterations", "20", "--seed", "2"],
    # The field's criteria (odotune/objectives/rl_innovations.h) in the same search,
    # with the held-out-fix guard and without it.
    "innovation-nll": ["--fitness", "innovation-nll", "--outage", "30"],
    "innovation-nll-free": ["--fitness", "innovation-nll", "--outage", "30", "--allow-worse-heldout"],
    "nis": ["--fitness", "nis", "--outage", "30"],
    "nis-free": ["--fitness", "nis", "--outage", "30", "--allow-worse-heldout"],
    "whiteness": ["--fitness", "whiteness", "--outage", "30"],
    "whiteness-free": ["--fitness", "whiteness", "--outage", "30", "--allow-worse-heldout"],
    "heldout-nll": ["--fitness", "heldout-nll", "--outage", "30"],
    "heldout-nll-free": ["--fitness", "heldout-nll", "--outage", "30", "--allow-worse-heldout"],
    "grid-every5": ["--fitness", "both", "--refine", "0", "--outage", "30", "--outage-every", "5"],
    "grid-blocks": ["--fitness", "both", "--space", "blocks", "--refine", "0", "--outage", "30"],
}


def windows(out, stem, params, t):
    path = f"{out}/{stem}-windows.json"
    if not os.path.exists(path):
        subprocess.run([BIN, "eval", "--rl-params", params, *BAG, "--from", f"{t}", "--until", f"{MID}", "--outages", "30,60",
                        "--outage-every", "5", "--json", path], check=True, stdout=subprocess.DEVNULL)
    return json.load(open(path))["simulated_outages"]["rmse_m"]


def run(out, name, flags, t):
    stem = f"{out}/{name}-{t:g}"
    if not os.path.exists(stem + ".json"):
        subprocess.run([BIN, "tune", "--rl-params", PARAMS, *BAG, "--no-input-covariances", "--until", f"{t}", "--end", f"{MID}", *flags, "--json", stem + ".json",
                        "--config-out", stem + ".yaml"], check=True, stdout=subprocess.DEVNULL)
    j = json.load(open(stem + ".json"))
    b, a = j["held_out"]["baseline"], j["held_out"]["tuned"]
    w = windows(out, f"{name}-{t:g}", stem + ".yaml", t) / windows(out, f"defaults-{t:g}", PARAMS, t)
    return (w, a["every_fifth_fix"]["rmse_m"] / b["every_fifth_fix"]["rmse_m"],
            a["outage"]["rmse_m"] / b["outage"]["rmse_m"], j["seconds"])


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "out/husky-rl-design"
    names = sys.argv[2:] or list(DESIGNS)
    os.makedirs(out, exist_ok=True)
    print("ratios tuned / defaults: windows, fifth (outage) per T; means; score = windows + fifth")
    print(f"{'design':14s} " + " ".join(f"{'T=' + format(t, 'g'):>20s}" for t in SPLITS) +
          f" {'mean':>13s} {'score':>6s} {'s':>6s}")
    for name in names:
        rows = [run(out, name, DESIGNS[name], t) for t in SPLITS]
        mw = sum(r[0] for r in rows) / len(rows)
        mf = sum(r[1] for r in rows) / len(rows)
        cells = " ".join(f"{r[0]:6.2f} {r[1]:5.2f} ({r[2]:5.2f})" for r in rows)
        print(f"{name:14s} {cells} {mw:6.2f} {mf:6.2f} {mw + mf:6.2f} {sum(r[3] for r in rows):6.0f}",
              flush=True)


if __name__ == "__main__":
    main()
