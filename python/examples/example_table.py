"""The worked example's tables, made from its own outputs, so that the docs cannot go stale.

Reads a `somnurbs run experiments/ch6_exact.toml --profile quick` folder (runs.csv and the
certificate exact_<grid>.csv), the IOH root of `external_optimisers.py` (each run's best) and the
folder `somnurbs compare RESULTS --external ROOT --out OUT` wrote (Friedman mean ranks in
compare_overall.csv, AOCC in compare_aocc.csv), and writes two Markdown tables: `full` (per
problem: B, the certified optimum, and each optimiser's mean best as the share of the way from B
to the optimum it did not go; then the mean ranks and AOCC) for docs/python.md, and `summary` (the
last two rows) for the README. Each lives in its file between the lines
`<!-- example-table:NAME -->` and `<!-- /example-table -->`.

    python example_table.py RESULTS IOH_ROOT COMPARE_OUT --check README.md docs/python.md
    python example_table.py RESULTS IOH_ROOT COMPARE_OUT --write README.md docs/python.md

--check exits 1, printing both versions, when a file's table is not what the outputs give;
--write puts the tables in; with neither, both tables are printed.
"""

import argparse
import csv
import glob
import json
import os
import re
import sys
from collections import defaultdict

NAMES = {"ga": "GA", "de": "DE", "pso": "PSO", "cma-es": "CMA-ES", "scipy-de": "scipy DE"}
BEGIN = "<!-- example-table:{} -->"
END = "<!-- /example-table -->"


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def problem_name(dataset, grid, net, param):
    return f"{dataset}_{grid}_{net}_{param}"


def cli_results(folder):
    """(problems in order, {problem: (label, dimension, B)}, {(problem, optimiser): [best]},
    optimisers)."""
    order, facts, best, opts = [], {}, defaultdict(list), []
    for r in read_csv(os.path.join(folder, "runs.csv")):
        name = problem_name(r["dataset"], f"{r['grid_x']}x{r['grid_y']}", f"{r['cn_x']}x{r['cn_y']}", r["parameterisation"])
        if name not in facts:
            order.append(name)
            facts[name] = (f"{r['dataset']} {r['cn_x']}x{r['cn_y']}", int(r["dimension"]), float(r["b"]))
        if r["optimiser"] not in opts:
            opts.append(r["optimiser"])
        best[(name, r["optimiser"])].append(float(r["best"]))
    return order, facts, best, opts


def certificates(folder):
    """{problem: (exact_f, lower_bound)} from every exact_<grid>.csv."""
    out = {}
    for path in sorted(glob.glob(os.path.join(folder, "exact_*.csv"))):
        grid = os.path.basename(path)[len("exact_"):-len(".csv")]
        for r in read_csv(path):
            name = problem_name(r["data"], grid, f"{r['cn_x']}x{r['cn_y']}", r["parameterisation"])
            out[name] = (float(r["exact_f"]), float(r["lower_bound"]))
    return out


def external_results(root, best):
    """Adds each external run's best to `best`; returns the optimisers in folder order."""
    opts = []
    for folder in sorted(p for p in glob.glob(os.path.join(root, "*")) if os.path.isdir(p)):
        for path in sorted(glob.glob(os.path.join(folder, "IOHprofiler_*.json"))):
            with open(path) as f:
                doc = json.load(f)
            name, opt = doc["function_name"], doc["algorithm"]["name"]
            if opt not in opts:
                opts.append(opt)
            for scenario in doc["scenarios"]:
                for run in scenario["runs"]:
                    best[(name, opt)].append(float(run["best"]["y"]))
    return opts


def compare_results(folder):
    """({optimiser: Friedman mean rank}, {optimiser: AOCC over all problems})."""
    ranks = {}
    for r in read_csv(os.path.join(folder, "compare_overall.csv")):
        ranks[r["x"]] = float(r["mean_rank_x"])
        ranks[r["y"]] = float(r["mean_rank_y"])
    aocc = {r["optimiser"]: float(r["aocc"]) for r in read_csv(os.path.join(folder, "compare_aocc.csv")) if r["group"] == "all"}
    return ranks, aocc


def tables(results, ioh_root, compare_out):
    order, facts, best, opts = cli_results(results)
    opts += [o for o in external_results(ioh_root, best) if o not in opts]
    certs = certificates(results)
    ranks, aocc = compare_results(compare_out)
    head = "| | " + " | ".join(NAMES.get(o, o) for o in opts) + " |"
    rule = "|---" * (len(opts) + 1) + "|"
    rank_row = "| Friedman mean rank (1 = least error) | " + " | ".join(f"{ranks[o]:.2f}" for o in opts) + " |"
    aocc_row = "| AOCC against the certified optimum's f | " + " | ".join(f"{aocc[o]:.3f}" for o in opts) + " |"
    summary = "\n".join([head, rule, rank_row, aocc_row])
    lines = [
        "| problem (variables) | B | certified optimum: f | gap f - lower_bound | " + " | ".join(NAMES.get(o, o) for o in opts) + " |",
        "|---" * (len(opts) + 4) + "|",
    ]
    for name in order:
        label, dim, b = facts[name]
        f, lb = certs[name]
        shares = []
        for o in opts:
            runs = best[(name, o)]
            mean = sum(runs) / len(runs)
            shares.append(f"{(mean - f) / (b - f):.3f}")
        lines.append(f"| {label} ({dim}) | {b:.9f} | {f:.9f} | {f - lb:.1e} | " + " | ".join(shares) + " |")
    blank = " | | | | "
    lines.append("| Friedman mean rank" + blank + " | ".join(f"{ranks[o]:.2f}" for o in opts) + " |")
    lines.append("| AOCC (all problems)" + blank + " | ".join(f"{aocc[o]:.3f}" for o in opts) + " |")
    return {"full": "\n".join(lines), "summary": summary}


def replaced(text, name, table, path):
    pattern = re.compile(re.escape(BEGIN.format(name)) + r"\n(?:.*?\n)?" + re.escape(END), re.S)
    if not pattern.search(text):
        return None
    return pattern.sub(lambda _m: f"{BEGIN.format(name)}\n{table}\n{END}", text)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results")
    ap.add_argument("ioh_root")
    ap.add_argument("compare_out")
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--check", nargs="+", metavar="FILE")
    mode.add_argument("--write", nargs="+", metavar="FILE")
    args = ap.parse_args(argv)
    made = tables(args.results, args.ioh_root, args.compare_out)
    files = args.check or args.write
    if not files:
        for name, table in made.items():
            print(f"{BEGIN.format(name)}\n{table}\n{END}\n")
        return 0
    stale = 0
    for path in files:
        with open(path) as f:
            text = f.read()
        new, found = text, False
        for name, table in made.items():
            r = replaced(new, name, table, path)
            if r is not None:
                new, found = r, True
        if not found:
            print(f"{path}: no <!-- example-table:... --> block", file=sys.stderr)
            return 2
        if new != text:
            if args.write:
                with open(path, "w") as f:
                    f.write(new)
                print(f"{path}: tables written")
            else:
                stale += 1
                print(f"{path}: the worked example's table is not what its outputs give; now:\n", file=sys.stderr)
                for name, table in made.items():
                    if BEGIN.format(name) in text:
                        print(f"{BEGIN.format(name)}\n{table}\n{END}\n", file=sys.stderr)
    return 1 if stale else 0


if __name__ == "__main__":
    sys.exit(main())
