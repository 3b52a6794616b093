#!/usr/bin/env python3
"""Recompute a plan folder's readings score from its CSVs alone, without the Rust code, and
compare it with the folder's `readings_score.csv` (docs/readings.md, "The readings score").

For every (reading, spec) row: each CSV of the spec's folder named like a published table in
experiments/reference/ is matched to it row by row on the key columns; every value column both
have (CPU seconds and generations left out) whose published value is finite and non-zero counts,
and counts as reproduced when ours/published lies in [0.8, 1.25]. Claims: the rows of the folder's
claims.csv with an `agreement` that are not about CPU time (`timing` = yes), and of those the
ones that agree.

    python3 scripts/readings_score.py results/thesis          # a full plan folder
    python3 scripts/readings_score.py results/thesis_quick    # the quick one (no evidence)

Exit status 1 when a recomputed row differs from readings_score.csv.
"""

import csv
import math
import pathlib
import sys

BAND = (0.8, 1.25)
KEYS = {"data", "n", "n_x", "n_y", "cn_x", "cn_y", "parameterisation", "statistic", "control_points"}
REFERENCE = pathlib.Path(__file__).resolve().parent.parent / "experiments" / "reference"


def scored(column):
    return not (column.startswith("cpu") or column.endswith("_s") or column == "generation")


def rows(path):
    with open(path, newline="") as f:
        r = csv.DictReader(f)
        return r.fieldnames or [], list(r)


def number(text):
    try:
        v = float(text)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def table_score(ours_path, published_path):
    pub_header, pub_rows = rows(published_path)
    our_header, our_rows = rows(ours_path)
    keys = [c for c in pub_header if c in KEYS]
    values = [c for c in pub_header if c not in KEYS and scored(c) and c in our_header]
    index = {}
    for r in our_rows:
        index.setdefault(tuple(r.get(k, "") for k in keys), r)
    cells = within = 0
    for p in pub_rows:
        mine = index.get(tuple(p.get(k, "") for k in keys))
        if mine is None:
            continue
        for c in values:
            o, q = number(mine.get(c)), number(p.get(c))
            if o is None or q is None or q == 0.0:
                continue
            cells += 1
            within += BAND[0] <= o / q <= BAND[1]
    return cells, within


def folder_score(folder):
    published = {p.stem: p for p in REFERENCE.glob("*.csv")}
    cells = within = claims = agree = 0
    for f in sorted(folder.glob("*.csv")):
        if f.stem in published:
            c, w = table_score(f, published[f.stem])
            cells, within = cells + c, within + w
    claims_csv = folder / "claims.csv"
    if claims_csv.exists():
        for r in rows(claims_csv)[1]:
            a = r.get("agreement", "") if r.get("timing") != "yes" else ""
            if a:
                claims += 1
                agree += a == "agrees"
    return cells, within, claims, agree


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    root = pathlib.Path(sys.argv[1])
    header, written = rows(root / "readings_score.csv")
    first = written[0]["reading"] if written else ""
    bad = 0
    for r in written:
        folder = root / r["spec"] if r["reading"] == first else root / "readings" / r["reading"] / r["spec"]
        got = folder_score(folder)
        want = tuple(int(r[k]) for k in ("published_cells", "within_band", "claims_with_source", "claims_agree"))
        share = f"{got[1] / got[0]:.1%}" if got[0] else "-"
        status = "ok" if got == want else f"DIFFERS (readings_score.csv: {want})"
        bad += got != want
        print(f"{r['reading']:<28} {r['spec']:<20} {got[0]:>6} cells, {got[1]:>6} within ({share}), claims {got[3]}/{got[2]}  {status}")
    print(f"{len(written) - bad} of {len(written)} rows recomputed equal")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
