#!/usr/bin/env python3
"""The tables of reproduce/learned-real.sh from its output folder (Markdown on
stdout): per dataset and held-out recording the learned and the calibrated
odometry against the nominal kinematics, the cross-validation's verdicts and
whether the held-out figures contradict them, the fusion with fixes, the slip
detector's flags and the retraining.
    python3 reproduce/learned-real-tables.py OUT "1 2 3"
"""
import glob
import json
import os
import sys

OUT = sys.argv[1]
SEEDS = sys.argv[2].split()
DATASETS = [
    ("optiodom", "OptiOdom (wheels)", ["train-dec23", "train-jan"]),
    ("mrclam", "MRCLAM (commands)", ["train-12", "train-13", "train-23"]),
    ("litw", "Lost in the Woods (measured twist)", ["train-first", "train-second"]),
]
METRICS = [("v_mae", "V MAE"), ("w_mae", "W MAE"), ("pos_rmse_10s_m", "XY 10 s"),
           ("pos_rmse_60s_m", "XY 60 s"), ("pos_rmse_m", "XY run")]


def load(path):
    with open(path) as f:
        return json.load(f)


def held_runs(dataset, fold):
    d = f"{OUT}/{dataset}/{fold}/seed{SEEDS[0]}"
    return sorted(os.path.basename(p)[5:-5] for p in glob.glob(f"{d}/eval-*.json"))


def ratio(a, b):
    return a / b if a is not None and b else float("nan")


def span(values, digits=2):
    values = [v for v in values if v == v]
    if not values:
        return "–"
    lo, hi = min(values), max(values)
    half = 0.5 * 10 ** -digits
    return f"{lo:.{digits}f}" if abs(hi - lo) < half else f"{lo:.{digits}f}–{hi:.{digits}f}"


def selection(dataset, fold, seed):
    m = load(f"{OUT}/{dataset}/{fold}/seed{seed}/model.json")
    return m["odometry"], m["provenance"].get("selection", {})


def odometry_table(dataset, title, folds, summary):
    print(f"### {title}\n")
    print("Ratios to the nominal kinematics on each held-out recording (learned: over seeds "
          + ", ".join(SEEDS) + "; < 1 is better).\n")
    print("| fold | held-out | odometry | " + " | ".join(m[1] for m in METRICS) + " | fused XY RMSE [m] |")
    print("|---|---|---|" + "---:|" * (len(METRICS) + 1))
    for fold in folds:
        for run in held_runs(dataset, fold):
            evals = [load(f"{OUT}/{dataset}/{fold}/seed{s}/eval-{run}.json") for s in SEEDS]
            k = evals[0]["kinematic"]
            fk = evals[0].get("fused", {}).get("kinematic", {}).get("pos_rmse_m")
            print(f"| {fold} | {run} | kinematic [m/s, rad/s, m] | "
                  + " | ".join(f"{k[m]:.4f}" for m, _ in METRICS) + (f" | {fk:.3f} |" if fk else " | – |"))
            c = evals[0].get("calibrated")
            if c:
                fc = evals[0].get("fused", {}).get("calibrated", {}).get("pos_rmse_m")
                print(f"| | | calibrated ÷ kinematic | " + " | ".join(f"{ratio(c[m], k[m]):.2f}" for m, _ in METRICS)
                      + (f" | {fc:.3f} |" if fc else " | – |"))
            fl = [e.get("fused", {}).get("learned", {}).get("pos_rmse_m") for e in evals]
            cells = []
            for m, _ in METRICS:
                rs = [ratio(e["learned"][m], e["kinematic"][m]) for e in evals]
                cells.append(span(rs))
                summary.setdefault(dataset, {}).setdefault(m, []).extend(rs)
                if c:
                    summary[dataset].setdefault("cal_" + m, []).extend(
                        ratio(e["learned"][m], e["calibrated"][m]) for e in evals)
            fused = span([f for f in fl if f is not None], 3) if any(fl) else "–"
            print(f"| | | learned ÷ kinematic | " + " | ".join(cells) + f" | {fused} |")
            summary[dataset].setdefault("recordings", []).append(
                (fold, run, [ratio(e["learned"]["pos_rmse_m"], e["kinematic"]["pos_rmse_m"]) for e in evals]))
    print()


def verdict_table(dataset, folds, contradictions):
    print("Cross-validation inside the training recordings, and the held-out figures:\n")
    print("| fold | seed | chosen | kept | folds' XY run ratio (chosen) | held-out contradicts it |")
    print("|---|---:|---|---|---|---|")
    for fold in folds:
        for s in SEEDS:
            odo, sel = selection(dataset, fold, s)
            st = sel.get("settings", {})
            label = f"{st.get('units')} units, {st.get('window')} steps, decay {st.get('weight_decay')}, {st.get('features')}"
            kept = sel.get("combination", "?")
            ratios = []
            for fm in sel.get("fold_measures", []):
                ratios.append(f"{fm['pose_rmse_chosen_m'][2] / fm['pose_rmse_kinematic_m'][2]:.2f}")
            bad = []
            for run in held_runs(dataset, fold):
                e = load(f"{OUT}/{dataset}/{fold}/seed{s}/eval-{run}.json")
                if odo["v_beats_kinematic"] and e["learned"]["v_mae"] > e["kinematic"]["v_mae"]:
                    bad.append(f"{run} V MAE")
                if odo["w_beats_kinematic"] and e["learned"]["w_mae"] > e["kinematic"]["w_mae"]:
                    bad.append(f"{run} W MAE")
                if kept != "kinematic" and e["learned"]["pos_rmse_m"] > e["kinematic"]["pos_rmse_m"]:
                    bad.append(f"{run} XY run")
            contradictions.extend((dataset, fold, s, b) for b in bad)
            print(f"| {fold} | {s} | {label} | {kept} | {', '.join(ratios)} | {', '.join(bad) or 'no'} |")
    print()


def slip_table(dataset, folds):
    print("Slip detector (no dataset has slip labels: what it flags, and the learned odometry's mean |error| "
          "on the flagged steps ÷ elsewhere), seed 1:\n")
    print("| fold | held-out | drive | flagged | V error ratio | W error ratio |")
    print("|---|---|---|---:|---:|---:|")
    for fold in folds:
        for run in held_runs(dataset, fold):
            e = load(f"{OUT}/{dataset}/{fold}/seed{SEEDS[0]}/eval-{run}.json").get("slip_detector")
            if not e:
                continue
            share = 100.0 * e["flagged"] / max(1, e["steps"])
            rv = ratio(e["v_abs_error_flagged"], e["v_abs_error_other"])
            rw = ratio(e["w_abs_error_flagged"], e["w_abs_error_other"])
            print(f"| {fold} | {run} | {e['drive']} | {share:.1f} % | {rv:.2f} | {rw:.2f} |")
    print()


def summary_section(summary, contradictions):
    print("## Summary\n")
    print("| dataset | worst V MAE ÷ kin. | worst W MAE ÷ kin. | worst XY run ÷ kin. | mean XY run ÷ kin. | "
          "recordings ≥ 10 % better (all seeds) | mean XY run ÷ calibrated |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for dataset, title, _ in DATASETS:
        s = summary.get(dataset, {})
        if not s:
            continue
        worst = [max(v for v in s[m] if v == v) for m in ("v_mae", "w_mae", "pos_rmse_m")]
        xy = [v for v in s["pos_rmse_m"] if v == v]
        better = sum(1 for _, _, rs in s["recordings"] if all(r <= 0.9 for r in rs))
        cal = [v for v in s.get("cal_pos_rmse_m", []) if v == v]
        cal_cell = f"{sum(cal) / len(cal):.3f}" if cal else "–"
        print(f"| {title} | {worst[0]:.3f} | {worst[1]:.3f} | {worst[2]:.3f} | {sum(xy) / len(xy):.3f} | "
              f"{better} of {len(s['recordings'])} | {cal_cell} |")
    print()
    print(f"Held-out figures contradicting a net kept by the cross-validation: {len(contradictions)}"
          + (": " + "; ".join(f"{d} {f} seed {s}: {b}" for d, f, s, b in contradictions) if contradictions else "")
          + "\n")


def paper_nets():
    print("### The paper's velocity nets on OptiOdom (seed 1), XY run ÷ kinematic\n")
    for fold in ("train-dec23", "train-jan"):
        rs = []
        for p in sorted(glob.glob(f"{OUT}/optiodom/{fold}/velocity/eval-*.json")):
            e = load(p)
            rs.append(f"{os.path.basename(p)[5:-5]} {ratio(e['learned']['pos_rmse_m'], e['kinematic']['pos_rmse_m']):.2f}")
        print(f"- {fold}: " + ", ".join(rs))
    print()


def retraining():
    print("### Retraining on a held-out recording's first half (reference: its ground truth at 10 Hz), "
          "judged on its second half\n")
    print("| dataset | recording | retrains | odometry | V MAE | W MAE | XY run [m] |")
    print("|---|---|---:|---|---:|---:|---:|")
    for dataset, fold, run in (("optiodom", "train-dec23", "020120212354_run-01"), ("mrclam", "train-12", "robot3"),
                               ("litw", "train-first", "litw-second-half")):
        d = f"{OUT}/{dataset}/{fold}/seed1"
        if not os.path.exists(f"{d}/retrain-{run}.json"):
            continue
        n = len(load(f"{d}/retrain-{run}.json")["retrains"])
        before = load(f"{d}/second-half-model-{run}.json")
        after = load(f"{d}/second-half-retrained-{run}-{run}.json")
        for name, e in (("kinematic", before["kinematic"]), ("learned", before["learned"]),
                        ("learned, retrained", after["learned"])):
            print(f"| {dataset} | {run} | {n} | {name} | {e['v_mae']:.4f} | {e['w_mae']:.4f} | {e['pos_rmse_m']:.3f} |")
    print()


def mean_errors(path):
    """Mean signed V and W errors (odometry − truth) of the learned and the
    kinematic odometry from an eval CSV: their biases [m/s, rad/s]."""
    sums = {k: [0.0, 0] for k in ("v_learned", "w_learned", "v_kinematic", "w_kinematic")}
    with open(path) as f:
        header = f.readline().strip().split(",")
        for line in f:
            c = dict(zip(header, line.rstrip("\n").split(",")))
            if not c.get("v_true") or not c.get("w_true"):
                continue
            for k in sums:
                truth = float(c[k[0] + "_true"])
                sums[k][0] += float(c[k]) - truth
                sums[k][1] += 1
    return {k: s / n for k, (s, n) in sums.items() if n}


def bias_table():
    print("### MRCLAM: each held-out robot's mean errors (bias) over its 900 s, seed 1\n")
    print("The whole-run position error of dead reckoning is set by the yaw-rate bias integrated over the run.\n")
    print("| held-out | V bias kinematic [m/s] | V bias learned | W bias kinematic [rad/s] | W bias learned | "
          "heading drift of the W bias over the run [rad] |")
    print("|---|---:|---:|---:|---:|---:|")
    for fold, run in (("train-12", "robot3"), ("train-13", "robot2"), ("train-23", "robot1")):
        path = f"{OUT}/mrclam/{fold}/seed{SEEDS[0]}/eval-{run}.csv"
        if not os.path.exists(path):
            continue
        b = mean_errors(path)
        print(f"| {run} | {b['v_kinematic']:+.4f} | {b['v_learned']:+.4f} | {b['w_kinematic']:+.5f} | "
              f"{b['w_learned']:+.5f} | {b['w_kinematic'] * 900:+.2f} → {b['w_learned'] * 900:+.2f} |")
    print()


def main():
    summary, contradictions = {}, []
    print("# Learned odometry on real recordings: the tables of reproduce/learned-real.sh\n")
    for dataset, title, folds in DATASETS:
        odometry_table(dataset, title, folds, summary)
        verdict_table(dataset, folds, contradictions)
        slip_table(dataset, folds)
    bias_table()
    paper_nets()
    retraining()
    summary_section(summary, contradictions)


main()
