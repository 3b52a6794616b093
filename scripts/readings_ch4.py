#!/usr/bin/env python3
"""Chapter 4 readings against Appendix B, independent of the Rust code (docs/readings.md,
"The 3-D SOM's TE and the spindle's QE").

For each run folder (a `ch4_models` folder holding appendix_b.csv, or a folder holding
ch4_models/), compares QE and TE with experiments/reference/appendix_b.csv cell by cell (data
set x n): the ratio ours / thesis per model (median, range, share within [0.8, 1.25]), the same
for the spindle alone, and in how many cells DNSOM has the lowest TE and the 3-D SOM the highest
(ties count, as in claims.csv; the thesis: 15 of 15 each).

    python3 scripts/readings_ch4.py results/baselines/full/ch4_models /work/scratch-ch4/layer
"""

import argparse
import csv
import statistics
import sys
from pathlib import Path

MODELS = ["som2d", "som3d", "cksom", "dnsom"]
LOW, HIGH = 0.8, 1.25


def read_table(path):
    with open(path, newline="") as f:
        return {(r["data"], r["n"]): r for r in csv.DictReader(f)}


def appendix_b(folder):
    folder = Path(folder)
    for p in (folder / "appendix_b.csv", folder / "ch4_models" / "appendix_b.csv"):
        if p.is_file():
            return read_table(p)
    sys.exit(f"{folder}: no appendix_b.csv (nor ch4_models/appendix_b.csv)")


def ratios(ours, ref, metric, model, data=None):
    out = []
    for key, r in ref.items():
        if key in ours and (data is None or key[0] == data):
            out.append(float(ours[key][f"{metric}_{model}"]) / float(r[f"{metric}_{model}"]))
    return out


def summary(rs):
    if not rs:
        return "no cells"
    inside = sum(LOW <= r <= HIGH for r in rs)
    return (f"median {statistics.median(rs):.2f}, range {min(rs):.2f}-{max(rs):.2f}, "
            f"{inside}/{len(rs)} in [{LOW}, {HIGH}]")


def extreme_count(table, keys, model, lowest):
    """Cells where `model`'s TE is the lowest (or highest) of the four models, ties included."""
    held, failed = 0, []
    for key in keys:
        te = {m: float(table[key][f"te_{m}"]) for m in MODELS}
        others = [te[m] for m in MODELS if m != model]
        ok = te[model] <= min(others) if lowest else te[model] >= max(others)
        held += ok
        if not ok:
            failed.append(f"{key[0]}/{key[1]}")
    return held, failed


def report(label, ours, ref):
    keys = [k for k in ref if k in ours]
    print(f"== {label} ({len(keys)} cells)")
    for metric in ("te", "qe"):
        for m in MODELS:
            print(f"  {metric.upper()} {m:6s} ours/thesis: {summary(ratios(ours, ref, metric, m))}")
    for metric in ("qe", "te"):
        for m in MODELS:
            rs = ratios(ours, ref, metric, m, data="spindle")
            print(f"  spindle {metric.upper()} {m:6s}: {summary(rs)}")
    for model, lowest, what in (("dnsom", True, "DNSOM has the lowest TE"),
                                ("som3d", False, "3-D SOM has the highest TE")):
        held, failed = extreme_count(ours, keys, model, lowest)
        thesis, _ = extreme_count(ref, keys, model, lowest)
        fails = f" (not in {', '.join(failed)})" if failed else ""
        print(f"  {what}: {held}/{len(keys)} here, {thesis}/{len(keys)} thesis{fails}")
    every = [r for metric in ("qe", "te") for m in MODELS for r in ratios(ours, ref, metric, m)]
    print(f"  all QE and TE cells: {summary(every)}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+", help="run folders (ch4_models or its parent)")
    ap.add_argument("--reference", default="experiments/reference/appendix_b.csv")
    args = ap.parse_args()
    ref = read_table(args.reference)
    for run in args.runs:
        report(run, appendix_b(run), ref)


if __name__ == "__main__":
    main()
