"""Load every run of a Chapter 6 results folder's IOHprofiler export (ioh/) with iohinspector,
the IOHprofiler group's Python loader, and check it against the folder's runs.csv: the number of
runs per (optimiser, problem), each run's evaluation count and final best value (from the JSON
meta-data and from the loaded .dat rows), and that every run's data starts at evaluation 1.
Exits 1 on any mismatch, 2 on bad usage. Run through scripts/check_ioh.sh, which pins the
iohinspector version."""

import csv
import math
from importlib.metadata import version
import sys
import warnings
from collections import defaultdict
from pathlib import Path


def main() -> int:
    if len(sys.argv) != 2:
        print("usage: check_ioh.py RESULTS_FOLDER (a Chapter 6 folder with runs.csv and ioh/)", file=sys.stderr)
        return 2
    folder = Path(sys.argv[1])
    runs_csv, ioh = folder / "runs.csv", folder / "ioh"
    if not runs_csv.is_file() or not ioh.is_dir():
        print(f"{folder}: needs runs.csv and ioh/", file=sys.stderr)
        return 2
    # Any loader warning (a file it skipped) is a failure.
    warnings.simplefilter("error")
    import iohinspector
    import polars as pl

    expected = defaultdict(list)
    with open(runs_csv, newline="") as f:
        for r in csv.DictReader(f):
            name = f"{r['dataset']}_{r['grid_x']}x{r['grid_y']}_{r['cn_x']}x{r['cn_y']}_{r['parameterisation']}"
            expected[(r["optimiser"], name)].append((int(r["repeat"]), int(r["evaluations"]), float(r["best"])))
    for v in expected.values():
        v.sort()

    dm = iohinspector.DataManager()
    try:
        dm.add_folder(str(ioh))
        ov = dm.overview
        data = dm.load(monotonic=True, include_meta_data=True)
    except Exception as e:  # a warning raised as an error: a file the loader skipped
        print(f"MISMATCH iohinspector could not load {ioh}: {e}")
        return 1
    errors = []
    got = defaultdict(list)
    for row in ov.sort(["algorithm_name", "function_name", "run_id"]).iter_rows(named=True):
        got[(row["algorithm_name"], row["function_name"])].append(row)
    if set(got) != set(expected):
        errors.append(f"(optimiser, problem) pairs differ: only in ioh/ {sorted(set(got) - set(expected))}, only in runs.csv {sorted(set(expected) - set(got))}")
    n_checked = 0
    for key in sorted(set(got) & set(expected)):
        exp, have = expected[key], got[key]
        if len(exp) != len(have):
            errors.append(f"{key}: {len(have)} runs loaded, runs.csv has {len(exp)}")
            continue
        for (repeat, evals, best), row in zip(exp, have):
            n_checked += 1
            where = f"{key} repeat {repeat} (data_id {row['data_id']})"
            if row["evals"] != evals:
                errors.append(f"{where}: evals {row['evals']} in the JSON, {evals} in runs.csv")
            if row["best_y"] != best:
                errors.append(f"{where}: best y {row['best_y']!r} in the JSON, {best!r} in runs.csv")
            rows = data.filter(pl.col("data_id") == row["data_id"]).sort("evaluations")
            if rows.height == 0:
                errors.append(f"{where}: no data rows loaded")
                continue
            first, last = rows["evaluations"][0], rows["evaluations"][-1]
            low = rows["raw_y"].min()
            if first != 1:
                errors.append(f"{where}: data start at evaluation {first}, not 1")
            if last > evals:
                errors.append(f"{where}: a data row at evaluation {last} past the run's {evals}")
            if not (low == best or (math.isinf(low) and math.isinf(best))):
                errors.append(f"{where}: least loaded raw_y {low!r}, runs.csv best {best!r}")
    total = sum(len(v) for v in expected.values())
    if ov.height != total:
        errors.append(f"iohinspector lists {ov.height} runs, runs.csv has {total}")
    for e in errors[:50]:
        print("MISMATCH", e)
    if errors:
        print(f"check_ioh: {len(errors)} mismatches ({n_checked} of {total} runs checked) in {folder}")
        return 1
    print(f"check_ioh: iohinspector {version('iohinspector')} loaded all {total} runs of {len(expected)} (optimiser, problem) pairs in {ioh}: counts, evaluations, final best values and first rows agree with runs.csv")
    return 0


if __name__ == "__main__":
    sys.exit(main())
