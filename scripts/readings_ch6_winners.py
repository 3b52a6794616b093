#!/usr/bin/env python3
"""Chapter 6 per control net: which optimiser has the least average error, and how far each
lowers approach B's error, ours beside the thesis' (issue 38; docs/readings.md, "PSO's
velocity clamp and position bound").

Reads only the tables (stdlib, independent of the Rust code): BASE/ch6_same/appendix_k.csv and
BASE/ch6_diff/appendix_l.csv (columns data, parameterisation, cn_x, cn_y, <opt>_avg, ..., b),
and the thesis' experiments/reference/appendix_k.csv and appendix_l.csv. With --pso DIR the
pso_avg column is taken from DIR/ch6_same and DIR/ch6_diff instead (a grid whose table DIR
lacks is skipped): a PSO-only run under another reading, from spec copies with
optimisers = ["pso"] (GA and DE do not depend on PSO's options, and every (cell, repeat) has its
own seed, so its PSO runs are the ones a full run would make).

Per net and grid it prints the number of cells (5 data sets x 4 parameterisations) where each
optimiser's average is strictly least (ties, at the tables' six decimals, counted apart), and
the median over those cells of (b - avg) / b per optimiser.

    python3 scripts/readings_ch6_winners.py results/baselines/full
    python3 scripts/readings_ch6_winners.py results/baselines/full --pso /tmp/r38/vdata
"""

import argparse
import csv
import statistics
import sys
from pathlib import Path

OPTS = ("ga", "de", "pso")
TABLES = (("20x20", "ch6_same", "appendix_k.csv"), ("18x30", "ch6_diff", "appendix_l.csv"))


def read(path):
    """{(data, parameterisation, net): row} of one appendix table."""
    with open(path, newline="") as f:
        return {(r["data"], r["parameterisation"], f"{r['cn_x']}x{r['cn_y']}"): r
                for r in csv.DictReader(f)}


def merged(base, pso):
    """Base rows with pso_avg (and b, checked equal) from the PSO-only table, if given."""
    if pso is None:
        return base
    out = {}
    for key, row in base.items():
        if key not in pso:
            sys.exit(f"cell {key} missing from the PSO table")
        if abs(float(pso[key]["b"]) - float(row["b"])) > 1e-9 * abs(float(row["b"])):
            sys.exit(f"cell {key}: b differs between the two tables")
        out[key] = dict(row, pso_avg=pso[key]["pso_avg"])
    return out


def winner(row):
    avg = {o: float(row[f"{o}_avg"]) for o in OPTS}
    least = min(avg.values())
    best = [o for o in OPTS if avg[o] == least]
    return best[0] if len(best) == 1 else "tie"


def improvement(row, opt):
    b = float(row["b"])
    return (b - float(row[f"{opt}_avg"])) / b


def summarise(rows):
    """{net: (winner counts, median improvement per optimiser)} in net order."""
    nets = sorted({k[2] for k in rows}, key=lambda n: tuple(int(v) for v in n.split("x")))
    out = {}
    for net in nets:
        cell = [r for k, r in rows.items() if k[2] == net]
        counts = {o: 0 for o in OPTS + ("tie",)}
        for r in cell:
            counts[winner(r)] += 1
        med = {o: statistics.median(improvement(r, o) for r in cell) for o in OPTS}
        out[net] = (counts, med)
    return out


def wins(counts):
    s = "/".join(str(counts[o]) for o in OPTS)
    return s + (f" ({counts['tie']} tied)" if counts["tie"] else "")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("base", type=Path, help="folder with ch6_same/ and ch6_diff/")
    ap.add_argument("--pso", type=Path, help="folder of a PSO-only run (ch6_same/, ch6_diff/)")
    ap.add_argument("--reference", type=Path,
                    default=Path(__file__).resolve().parent.parent / "experiments" / "reference")
    a = ap.parse_args()
    total_ours = {o: 0 for o in OPTS + ("tie",)}
    total_thesis = dict(total_ours)
    print("| grid | net | wins GA/DE/PSO ours | thesis | median (b-avg)/b GA, DE, PSO ours "
          "| thesis |")
    print("|---|---|---|---|---|---|")
    for grid, spec, table in TABLES:
        base = read(a.base / spec / table)
        if a.pso and not (a.pso / spec / table).exists():
            print(f"| {grid} | (no {spec}/{table} in {a.pso}) | | | | |")
            continue
        pso = read(a.pso / spec / table) if a.pso else None
        ours = summarise(merged(base, pso))
        thesis = summarise(read(a.reference / table))
        for net, (counts, med) in ours.items():
            tcounts, tmed = thesis[net]
            for o in total_ours:
                total_ours[o] += counts[o]
                total_thesis[o] += tcounts[o]
            fmt = ", ".join(f"{med[o]:.2g}" for o in OPTS)
            tfmt = ", ".join(f"{tmed[o]:.2g}" for o in OPTS)
            print(f"| {grid} | {net} | {wins(counts)} | {wins(tcounts)} | {fmt} | {tfmt} |")
    print(f"\nall cells listed, GA/DE/PSO: ours {wins(total_ours)}, thesis {wins(total_thesis)}")


if __name__ == "__main__":
    main()
