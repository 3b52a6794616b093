#!/usr/bin/env python3
"""A PSO-only copy of a Chapter 6 spec with [optim.pso] keys added (issue 38; docs/readings.md,
"PSO's velocity clamp and position bound"), for scripts/readings_ch6_winners.py --pso.

The keys go into the file, not through `run --set`, which would change every cell's seed: the
copy keeps the spec's seeds, so its PSO runs are the ones a full run under those keys makes.
The maps path is made absolute (recomputed from [optim.som] if missing, as in the spec).

    python3 scripts/readings_ch6_pso_spec.py experiments/ch6_same.toml /tmp/r38/v25_same.toml \\
        vmax_fraction=0.25
    somnurbs run /tmp/r38/v25_same.toml --jobs 1 --out /tmp/r38/v25/ch6_same
"""

import sys
from pathlib import Path


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    spec, out, *pairs = sys.argv[1:]
    spec = Path(spec).resolve()
    s = spec.read_text()
    for old, new in [
        ('optimisers = ["ga", "de", "pso"]', 'optimisers = ["pso"]'),
        ('maps = "../results/ch4_models/maps"',
         f'maps = "{(spec.parent / "../results/ch4_models/maps").resolve()}"'),
    ]:
        if old not in s:
            sys.exit(f"{spec}: no line {old!r}")
        s = s.replace(old, new, 1)
    header = s.index("[optim.pso]")
    line_end = s.index("\n", header) + 1
    keys = "".join(f"{k} = {v}\n" for k, v in (p.split("=", 1) for p in pairs))
    Path(out).write_text(s[:line_end] + keys + s[line_end:])


if __name__ == "__main__":
    main()
