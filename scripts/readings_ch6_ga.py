#!/usr/bin/env python3
"""Chapter 6's GA against the thesis' (docs/readings.md, "The last disagreements"), from tables
alone, independent of the Rust code.

For each folder holding appendix_k.csv (20x20) and/or appendix_l.csv (18x30), per control net:
the median over the cells (data set x parameterisation) of B - GA's average error, ours over the
thesis' (how many times more GA lowers B's error here), and the cells where GA's average ends
above B, ours and the thesis'; with the folder's runs.csv, GA's start: the median over its runs
of (best of the initial population - B) / B and the runs that start above B.

    python3 scripts/readings_ch6_ga.py results/baselines/full/ch6_same results/baselines/full/ch6_diff

GA alone under another setting (about 40 s on one core for ch6_same):

    sed -e 's/^optimisers = .*/optimisers = ["ga"]/' experiments/ch6_same.toml > /tmp/ga.toml
    somnurbs run /tmp/ga.toml --set optimise.ga.pm=0.005 --out /tmp/ga_pm0.005
    python3 scripts/readings_ch6_ga.py /tmp/ga_pm0.005
"""

import csv
import statistics
import sys
from collections import defaultdict
from pathlib import Path

REFERENCE = Path(__file__).resolve().parent.parent / "experiments" / "reference"
KEY = ("data", "parameterisation", "cn_x", "cn_y")


def read(path):
    with open(path, newline="") as f:
        return {tuple(r[k] for k in KEY): r for r in csv.DictReader(f)}


def main(folders):
    if not folders:
        sys.exit(__doc__)
    for folder in folders:
        for table in ("appendix_k", "appendix_l"):
            path = Path(folder) / f"{table}.csv"
            if not path.is_file():
                continue
            ours, ref = read(path), read(REFERENCE / f"{table}.csv")
            ratio, above, above_t = defaultdict(list), defaultdict(int), defaultdict(int)
            for k, r in ours.items():
                net = (int(k[2]), int(k[3]))
                t = ref.get(k)
                gain = float(r["b"]) - float(r["ga_avg"])
                above[net] += gain < 0
                if t is None:
                    continue
                gain_t = float(t["b"]) - float(t["ga_avg"])
                above_t[net] += gain_t < 0
                if gain_t > 0:
                    ratio[net].append(gain / gain_t)
            cells = []
            for net in sorted(set(ratio) | set(above)):
                r = f"{statistics.median(ratio[net]):.2f}" if ratio[net] else "-"
                cells.append(f"{net[0]}x{net[1]} {r} (above B {above[net]}, thesis {above_t[net]})")
            print(f"{folder} {table}: " + "; ".join(cells))
        starts(Path(folder) / "runs.csv")


def starts(path):
    """GA's initial best against B per net, from runs.csv (when there)."""
    if not path.is_file():
        return
    by = defaultdict(list)
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            if r["optimiser"] == "ga":
                b = float(r["b"])
                by[(int(r["cn_x"]), int(r["cn_y"]))].append((float(r["initial_best"]) - b) / b)
    cells = [
        f"{n[0]}x{n[1]} {statistics.median(v):+.1e} ({sum(x > 0 for x in v)}/{len(v)} above B)"
        for n, v in sorted(by.items())
    ]
    print(f"{path} GA's start: " + "; ".join(cells))


if __name__ == "__main__":
    main(sys.argv[1:])
