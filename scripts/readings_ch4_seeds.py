#!/usr/bin/env python3
"""Chapter 4 over map seeds: how much of the distance to Appendices B and C is one SOM run's draw
(docs/readings.md, "The last disagreements"). Independent of the Rust code.

Given several `ch4_models` run folders of the same spec with different master seeds (each cell
one SOM run, as in the thesis), for Appendix B (n x n, four models) and C (nx != ny, CKSOM and
DNSOM) and each statistic (min_error, max_error, qe, te) and model it prints

- against the thesis: the cells whose ratio ours / published lies in [0.8, 1.25], median and
  range over the folders, and the median ratio;
- seed against seed: the same share between every two of our folders (how often this code,
  reproducing itself with another seed, lands in the band: the most agreement one run can have).

    for s in $(seq 2023 2032); do
      mkdir -p /tmp/r4/$s
      sed -e "s/^master_seed = 2023/master_seed = $s/" -e 's/^save_maps = .*/save_maps = []/' \\
          experiments/ch4_models.toml > /tmp/r4/$s/ch4.toml
      somnurbs run /tmp/r4/$s/ch4.toml --jobs 1 --out /tmp/r4/$s/ch4_models
    done
    python3 scripts/readings_ch4_seeds.py /tmp/r4/*/ch4_models
"""

import csv
import itertools
import statistics
import sys
from pathlib import Path

REFERENCE = Path(__file__).resolve().parent.parent / "experiments" / "reference"
TABLES = {
    "appendix_b": (("data", "n"), ["som2d", "som3d", "cksom", "dnsom"]),
    "appendix_c": (("data", "n_x", "n_y"), ["cksom", "dnsom"]),
}
STATS = ["min_error", "max_error", "qe", "te"]
LOW, HIGH = 0.8, 1.25


def read(path, keys):
    with open(path, newline="") as f:
        return {tuple(r[k] for k in keys): r for r in csv.DictReader(f)}


def in_band(a, b, column):
    """(cells with a/b in the band, cells) over the keys both tables hold."""
    both = [k for k in b if k in a and float(b[k][column]) != 0.0]
    inside = sum(LOW <= float(a[k][column]) / float(b[k][column]) <= HIGH for k in both)
    return inside, len(both)


def median_ratio(a, b, column):
    return statistics.median(float(a[k][column]) / float(b[k][column]) for k in b if k in a)


def main(folders):
    if len(folders) < 2:
        sys.exit(__doc__)
    for table, (keys, models) in TABLES.items():
        ref = read(REFERENCE / f"{table}.csv", keys)
        runs = [read(Path(f) / f"{table}.csv", keys) for f in folders]
        print(f"== {table}: {len(runs)} seeds, {len(ref)} published rows")
        print(f"  {'statistic':16s} {'vs thesis: in band (median [min, max])':42s} {'median ratio':14s} seed vs seed: in band")
        for stat in STATS:
            for m in models:
                col = f"{stat}_{m}"
                vs = [in_band(r, ref, col) for r in runs]
                n = vs[0][1]
                ins = sorted(v[0] for v in vs)
                ratio = statistics.median(median_ratio(r, ref, col) for r in runs)
                pairs = [in_band(a, b, col) for a, b in itertools.permutations(runs, 2)]
                self_share = sum(p[0] for p in pairs) / max(sum(p[1] for p in pairs), 1)
                print(f"  {col:16s} {statistics.median(ins):5.1f}/{n} [{ins[0]}, {ins[-1]}]{'':26s} {ratio:6.3f}         {self_share:6.1%}")


if __name__ == "__main__":
    main(sys.argv[1:])
