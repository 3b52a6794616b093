"""Load an IOHprofiler folder written through somnurbs.ioh_adapter.Logger (the worked example's)
with iohinspector, the IOHprofiler group's loader, and check what it reads: every (algorithm,
problem) has RUNS runs of EVALUATIONS evaluations, the somnurbs experiment attributes come through,
and every run's best is at or above the problem's certified lower bound (the JSON run attribute).
Usage: check_python_ioh.py FOLDER RUNS EVALUATIONS. Exits 1 on a mismatch."""

import json
import sys
import warnings
from pathlib import Path


def main() -> int:
    folder, runs, evals = Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
    warnings.simplefilter("error")  # a file the loader skipped is a failure
    import iohinspector

    dm = iohinspector.DataManager()
    dm.add_folder(str(folder))
    ov = dm.overview
    dm.load(monotonic=True, include_meta_data=True)
    errors = []
    bounds = {}
    for f in folder.glob("*/IOHprofiler_*.json"):
        d = json.loads(f.read_text())
        for r in d["scenarios"][0]["runs"]:
            bounds[(d["algorithm"]["name"], d["function_name"])] = r["somnurbs_bound"]
    for col in ["somnurbs_spec", "somnurbs_profile", "somnurbs_reading", "somnurbs_box"]:
        if col not in ov.columns:
            errors.append(f"iohinspector's overview has no {col}")
    pairs = {}
    for row in ov.iter_rows(named=True):
        key = (row["algorithm_name"], row["function_name"])
        pairs[key] = pairs.get(key, 0) + 1
        if row["evals"] != evals:
            errors.append(f"{key} run {row['run_id']}: {row['evals']} evaluations, want {evals}")
        if row["best_y"] < bounds[key]:
            errors.append(f"{key} run {row['run_id']}: best {row['best_y']!r} below the certified bound {bounds[key]!r}")
    if set(pairs) != set(bounds) or any(n != runs for n in pairs.values()):
        errors.append(f"runs per (algorithm, problem) {pairs}, want {runs} for each of {sorted(bounds)}")
    for e in errors:
        print("MISMATCH", e)
    print(f"iohinspector {iohinspector.__version__ if hasattr(iohinspector, '__version__') else ''}: "
          f"{len(ov)} runs of {len(pairs)} (algorithm, problem) pairs loaded from {folder}"
          + ("" if errors else "; counts, evaluations and bounds check"))
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
