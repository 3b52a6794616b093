#!/usr/bin/env python3
"""Load a `somnurbs export` folder's surfaces.igs in gmsh (OpenCASCADE's IGES reader) and check it.

Usage: check_export_gmsh.py EXPORT_DIR [--frame-only]

Evaluates each imported surface at the data parameters of parameters.csv and sums the distances
to the data points there (Eq. 6.2: the bottom view's points, the top view's interior). With the
export in the map's frame (`--frame normalised`) that sum is the record's surface error, which
export.csv holds: they must agree to 1e-9 relative. In any frame, every data point must lie within
a tenth of the data's bounding-box diagonal from the surface at its parameters (the net lies on
the data in the data's own frame, not in another). Exit 0 when both hold; prints what it measured.
"""

import csv
import math
import sys
from pathlib import Path

import gmsh


def main() -> int:
    folder = Path(sys.argv[1])
    rows = list(csv.DictReader(open(folder / "parameters.csv")))
    summary = next(csv.DictReader(open(folder / "export.csv")))
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.occ.importShapes(str(folder / "surfaces.igs"))
    gmsh.model.occ.synchronize()
    surfaces = [tag for dim, tag in gmsh.model.getEntities(2)]
    if len(surfaces) != 2:
        print(f"expected 2 surfaces in surfaces.igs, gmsh found {len(surfaces)}")
        return 1
    views = dict(zip(["bottom", "top"], surfaces))
    points = [[float(r[k]) for k in "xyz"] for r in rows]
    lo = [min(p[a] for p in points) for a in range(3)]
    hi = [max(p[a] for p in points) for a in range(3)]
    diagonal = math.dist(lo, hi)
    total, worst = 0.0, 0.0
    for r, p in zip(rows, points):
        s = gmsh.model.getValue(2, views[r["view"]], [float(r["u"]), float(r["v"])])
        d = math.dist(p, s)
        total += d
        worst = max(worst, d)
    gmsh.finalize()
    recorded = float(summary["surface_error"])
    print(
        f"gmsh/OpenCASCADE: 2 surfaces; error at the data parameters {total!r} "
        f"(export.csv {recorded!r}); largest distance {worst:.3e}, data diagonal {diagonal:.3e}; "
        f"frame {summary['frame']}"
    )
    ok = worst <= 0.1 * diagonal
    if summary["frame"] in ("normalised", "map"):
        ok = ok and abs(total - recorded) <= 1e-9 * max(1.0, abs(recorded))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
