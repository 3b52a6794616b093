#!/usr/bin/env python3
"""The figures docs/readings.md compares for the seed readings, from run folders' runs.csv alone
(independent of the Rust report code).

    python3 scripts/readings_seeds.py seed003 DIR [DIR ...]
    python3 scripts/readings_seeds.py seed004 DIR [DIR ...]

DIR is a `somnurbs run` output folder (runs.csv in it, or in its seed003_cuckoo_bezier/ or
seed004_cylinder/ sub-folder, as `reproduce` writes them).

seed003: per example and method, the mean and best Y (Eq. 4/5) over the runs, and each method's
mean Y over the best classical method's (centripetal in the paper) beside the paper's Table 4
ratio. A folder without the classical methods is set against the first folder's.
seed004: per number of control points, the analytical RMS, the GA's least RMS over the repeats,
the gain 100 (analytical - GA) / analytical (the paper's 5.7471% at 7 control points: 0.0174 vs
0.0164) and the paper's Table III best fitness; then where the GA ends below the analytical net
and how many Table III cells lie within [0.8, 1.25] of the paper (the readings score's band).
"""

import csv
import math
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REF = os.path.join(ROOT, "experiments", "reference")
SUB = {"seed003": "seed003_cuckoo_bezier", "seed004": "seed004_cylinder"}
CLASSICAL = ["uniform", "chordal", "centripetal"]
SEARCHES = ["csa", "icsa"]


def runs_csv(folder, seed):
    for cand in (folder, os.path.join(folder, SUB[seed])):
        path = os.path.join(cand, "runs.csv")
        if os.path.isfile(path):
            with open(path, newline="") as f:
                return list(csv.DictReader(f))
    sys.exit(f"readings_seeds: no runs.csv in {folder} or {folder}/{SUB[seed]}")


def reference(name):
    with open(os.path.join(REF, name), newline="") as f:
        return list(csv.DictReader(f))


def seed003_paper():
    """{example: {method: Y mean}} from Table 4."""
    out = {}
    for r in reference("seed003_table4.csv"):
        if r["statistic"] == "y_mean":
            out[r["example"]] = {m: float(r[m]) for m in CLASSICAL + SEARCHES}
    return out


def seed003_stats(rows):
    """{example: {method: (mean Y, best Y, runs)}}."""
    ys = {}
    for r in rows:
        ys.setdefault(r["example"], {}).setdefault(r["method"], []).append(float(r["y"]))
    return {
        e: {m: (sum(v) / len(v), min(v), len(v)) for m, v in by.items()} for e, by in ys.items()
    }


def seed003(folders):
    paper = seed003_paper()
    stats = [(f, seed003_stats(runs_csv(f, "seed003"))) for f in folders]
    # A folder that ran CSA/ICSA alone (a start reading) is set against the classical methods of
    # the first folder that ran them (the same data: the noise streams do not depend on the start).
    shared = {}
    for _, st in stats:
        for e, by in st.items():
            for m in CLASSICAL:
                if m in by:
                    shared.setdefault(e, {}).setdefault(m, by[m])
    print("folder,example,method,runs,y_mean,y_best,mean_over_best_classical,paper_ratio")
    for folder, st in stats:
        for e, by in sorted(st.items()):
            classical = {m: by.get(m, shared.get(e, {}).get(m)) for m in CLASSICAL}
            classical = {m: v for m, v in classical.items() if v}
            best_c = min(classical.values(), key=lambda v: v[0])[0] if classical else math.nan
            p_best = min(paper[e][m] for m in CLASSICAL)
            for m in CLASSICAL + SEARCHES:
                if m not in by:
                    continue
                mean, best, n = by[m]
                print(
                    f"{folder},{e},{m},{n},{mean:.6g},{best:.6g},"
                    f"{mean / best_c:.4f},{paper[e][m] / p_best:.4f}"
                )


def seed004(folders):
    paper = {int(r["control_points"]): float(r["best_fitness"]) for r in reference("seed004_table3.csv")}
    print("folder,control_points,analytical_rms,ga_least_rms,gain_pct,paper_best_fitness,paper_gain_pct")
    for folder in folders:
        by = {}
        for r in runs_csv(folder, "seed004"):
            cp = int(r["control_points"])
            an, ga = float(r["analytical_rms"]), float(r["best_rms"])
            prev = by.get(cp, (an, math.inf))
            by[cp] = (an, min(prev[1], ga))
        for cp, (an, ga) in sorted(by.items()):
            gain = 100.0 * (an - ga) / an
            p = paper.get(cp, math.nan)
            # The paper states the analytical error at 7 control points only (0.0174).
            p_gain = 100.0 * (0.0174 - p) / 0.0174 if cp == 7 else math.nan
            print(f"{folder},{cp},{an:.6g},{ga:.6g},{gain:.3f},{p:.6g},{p_gain:.3f}")
        within = [cp for cp, (_, ga) in by.items() if cp in paper and 0.8 <= ga / paper[cp] <= 1.25]
        beats = [cp for cp, (an, ga) in sorted(by.items()) if ga < an]
        print(f"# {folder}: GA below analytical at {beats or 'none'}; "
              f"Table III cells with GA/paper in [0.8, 1.25]: {len(within)}/{len(paper)} {sorted(within)}")


def main(argv):
    if len(argv) < 3 or argv[1] not in SUB:
        sys.exit(__doc__)
    {"seed003": seed003, "seed004": seed004}[argv[1]](argv[2:])


if __name__ == "__main__":
    main(sys.argv)
