#!/usr/bin/env python3
"""A PSO-only copy of a Chapter 6 spec with [optimise.pso] keys added (issue 38; docs/readings.md,
"PSO's velocity clamp and position bound"), for scripts/readings_ch6_winners.py --pso.

The keys go into the file, not through `run --set`, which would change every cell's seed: the
copy keeps the spec's seeds, so its PSO runs are the ones a full run under those keys makes.
The maps path is made absolute (recomputed from [optimise.som] if missing, as in the spec).

    python3 scripts/readings_ch6_pso_spec.py experiments/ch6_same.toml /tmp/r38/v50_same.toml \\
        vmax_fraction=0.5
    somnurbs run /tmp/r38/v50_same.toml --jobs 1 --out /tmp/r38/v50/ch6_same
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
    lines = s.splitlines(keepends=True)
    start = next(i for i, l in enumerate(lines) if l.startswith("[optimise.pso]")) + 1
    end = next((i for i in range(start, len(lines)) if lines[i].startswith("[")), len(lines))
    for k, v in (p.split("=", 1) for p in pairs):
        k = k.strip()
        line = f"{k} = {v.strip()}\n"
        # A key the spec sets already is replaced (TOML forbids it twice), a new one added.
        at = [i for i in range(start, end) if lines[i].split("=", 1)[0].strip() == k]
        if at:
            lines[at[0]] = line
        else:
            lines.insert(start, line)
            end += 1
    Path(out).write_text("".join(lines))


if __name__ == "__main__":
    main()
