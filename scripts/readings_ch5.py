#!/usr/bin/env python3
"""Chapter 5's verdict counts of one or more run folders, from their runs.csv alone.

Independent of the Rust report code: for each folder holding `ch5_same/runs.csv` and/or
`ch5_diff/runs.csv` (a reproduction's output, or a spec's own folder holding `runs.csv`), it
counts per grid

- the control nets (per data set) where each parameterisation gives approach A, and B, the least
  surface error (Tables 5.4/5.5 and 5.7/5.8; no ties with real errors: a tie would go to none),
- the cells (data set, net, parameterisation) where B's error is below A's (Tables 5.6, 5.9),
- the cells whose least-error parameterisation is the thesis' own (Appendix E/F, per approach),
- the share of Appendix E/F's value cells whose ratio ours / published lies in [0.8, 1.25],

and prints them beside the thesis' counts over Appendix E/F's own numbers (`--brief`: one line
per folder; per data set, the median ratio ours / published and the cells in the band; "rival" is the most wins of any other parameterisation, "same" the nets whose winner
is the thesis' for A/B, "BA" the cells where B beats A, "share" the ratio share; `--spread`: the
least, median, greatest and mean of each figure over the folders given, e.g. one per map seed).

    python3 scripts/readings_ch5.py results/baselines/full /work/scratch-ch5/alpha07 ...

`--spec SPEC OUT [map_seed=N] [key=value ...]` writes a copy of a Chapter 5 spec with the keys
added to its [fit] section (a string value quoted: 'param_rows="middle"'), no `maps` folder (every
map is recomputed from [fit.som], which gives Chapter 4's maps bit for bit) and, with `map_seed`,
[fit.som]'s master seed changed (other maps of the same data sets and settings), no pictures:

    python3 scripts/readings_ch5.py --spec experiments/ch5_same.toml /tmp/s.toml map_seed=2024 \
        exponential_alpha=0.9
    somnurbs run /tmp/s.toml --jobs 1 --out /tmp/r/s2024/ch5_same
"""

import csv
import os
import statistics
import sys

PARAMS = ["uniform", "chord_length", "centripetal", "exponential"]
APPROACHES = ["A", "B"]
GRIDS = {"ch5_same": ("20x20", "appendix_e.csv"), "ch5_diff": ("18x30", "appendix_f.csv")}
REFERENCE = os.path.join(os.path.dirname(__file__), "..", "experiments", "reference")
SCORE_BAND = (0.8, 1.25)


def thesis_errors(name):
    """{(data, cn_x, cn_y, param, approach): error} of a published appendix."""
    out = {}
    with open(os.path.join(REFERENCE, name), newline="") as f:
        for r in csv.DictReader(f):
            for p in PARAMS:
                for a in APPROACHES:
                    v = r.get(f"{p}_{a}", "")
                    if v:
                        out[(r["data"], int(r["cn_x"]), int(r["cn_y"]), p, a)] = float(v)
    return out


def run_errors(path):
    """{(data, cn_x, cn_y, param, approach): error} of a runs.csv."""
    out = {}
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            key = (r["dataset"], int(r["cn_x"]), int(r["cn_y"]), r["parameterisation"], r["approach"])
            out[key] = float(r["surface_error"])
    return out


def nets(errors):
    return sorted({k[:3] for k in errors})


def winners(errors, approach):
    """{(data, cn_x, cn_y): the parameterisation with the least error, or None on a tie}."""
    out = {}
    for net in nets(errors):
        vals = [(errors[net + (p, approach)], p) for p in PARAMS if net + (p, approach) in errors]
        if len(vals) < 2:
            continue
        vals.sort()
        out[net] = None if vals[0][0] == vals[1][0] else vals[0][1]
    return out


def counts(errors, keep):
    """Wins per parameterisation (A and B) and B's wins over A, over the nets in `keep`."""
    res = {}
    for a in APPROACHES:
        w = winners(errors, a)
        res[a] = {p: sum(1 for n, x in w.items() if n in keep and x == p) for p in PARAMS}
    b_beats = sum(
        1
        for n in keep
        for p in PARAMS
        if n + (p, "A") in errors and n + (p, "B") in errors and errors[n + (p, "B")] < errors[n + (p, "A")]
    )
    pairs = sum(1 for n in keep for p in PARAMS if n + (p, "A") in errors and n + (p, "B") in errors)
    return res, b_beats, pairs


def score_share(ours, thesis):
    """Share of the published value cells with ours / published in SCORE_BAND (matched by key)."""
    both = [k for k in thesis if k in ours and thesis[k] != 0.0]
    inside = sum(1 for k in both if SCORE_BAND[0] <= ours[k] / thesis[k] <= SCORE_BAND[1])
    return inside, len(both)


def same_winner(ours, thesis, keep):
    """Nets (per approach) where our least-error parameterisation is the thesis' one."""
    out = {}
    for a in APPROACHES:
        wo, wt = winners(ours, a), winners(thesis, a)
        out[a] = sum(1 for n in keep if wo.get(n) is not None and wo.get(n) == wt.get(n))
    return out


def fmt_wins(w):
    return " ".join(f"{p[:5]} {w[p]:2d}" for p in PARAMS)


def measures(folder):
    """{(grid, measure): value} of one folder, the figures `--spread` summarises."""
    out = {}
    for spec, (grid, appendix) in GRIDS.items():
        path = os.path.join(folder, spec, "runs.csv")
        if not os.path.exists(path):
            continue
        ours, thesis = run_errors(path), thesis_errors(appendix)
        keep = [n for n in nets(ours) if n in set(nets(thesis))]
        ow, ob, _ = counts(ours, keep)
        inside, total = score_share(ours, thesis)
        same = same_winner(ours, thesis, keep)
        out[(grid, "exponential wins A")] = ow["A"]["exponential"]
        out[(grid, "chord_length wins A")] = ow["A"]["chord_length"]
        out[(grid, "chord_length wins B")] = ow["B"]["chord_length"]
        out[(grid, "exponential wins B")] = ow["B"]["exponential"]
        out[(grid, "A: exponential holds")] = int(ow["A"]["exponential"] >= max(ow["A"].values()))
        out[(grid, "B: chord_length holds")] = int(ow["B"]["chord_length"] >= max(ow["B"].values()))
        out[(grid, "same winner A")] = same["A"]
        out[(grid, "same winner B")] = same["B"]
        out[(grid, "B beats A")] = ob
        out[(grid, "ratio share")] = inside / max(total, 1)
        for data, (median, inside_d, total_d) in per_data(ours, thesis).items():
            out[(grid, f"{data}: median ratio")] = median
            out[(grid, f"{data}: share in band")] = inside_d / max(total_d, 1)
    return out


def per_data(ours, thesis):
    """{data: (median ratio ours / published, cells in SCORE_BAND, cells)} over Appendix E/F's
    value cells of each data set."""
    out = {}
    for data in sorted({k[0] for k in thesis}):
        r = sorted(ours[k] / thesis[k] for k in thesis if k[0] == data and k in ours and thesis[k] != 0.0)
        if r:
            mid = statistics.median(r)
            inside = sum(1 for x in r if SCORE_BAND[0] <= x <= SCORE_BAND[1])
            out[data] = (mid, inside, len(r))
    return out


def spread(folders):
    """Min, median, max (and mean) of each measure over `folders` (e.g. one per map seed)."""
    rows = [measures(f) for f in folders]
    keys = sorted({k for r in rows for k in r})
    print(f"{len(rows)} folders")
    for k in keys:
        v = sorted(r[k] for r in rows if k in r)
        mid = statistics.median(v)
        print(f"  {k[0]} {k[1]:24s} min {v[0]:7.3f} median {mid:7.3f} max {v[-1]:7.3f} mean {sum(v) / len(v):7.3f}")


def report(folder, brief=False):
    line = [folder]
    for spec, (grid, appendix) in GRIDS.items():
        path = os.path.join(folder, spec, "runs.csv")
        if not os.path.exists(path):
            if os.path.basename(os.path.normpath(folder)) == spec:
                path = os.path.join(folder, "runs.csv")
            if not os.path.exists(path):
                continue
        ours, thesis = run_errors(path), thesis_errors(appendix)
        keep = [n for n in nets(ours) if n in set(nets(thesis))]
        (ow, ob, op), (tw, tb, tp) = counts(ours, keep), counts(thesis, keep)
        inside, total = score_share(ours, thesis)
        same = same_winner(ours, thesis, keep)
        if brief:
            line.append(
                f"{grid}: expA {ow['A']['exponential']:2d} (rival {max(v for p, v in ow['A'].items() if p != 'exponential'):2d}) "
                f"chordB {ow['B']['chord_length']:2d} (rival {max(v for p, v in ow['B'].items() if p != 'chord_length'):2d}) "
                f"same {same['A']:2d}/{same['B']:2d} BA {ob:3d} share {inside / max(total, 1):.3f}"
            )
            continue
        print(f"{folder} {spec} ({grid}, {len(keep)} nets)")
        for a, best in (("A", "exponential"), ("B", "chord_length")):
            print(
                f"  {a}: ours  {fmt_wins(ow[a])} | {best} {ow[a][best]}/{len(keep)} "
                f"(thesis {tw[a][best]}/{len(keep)}); same winner as the thesis in {same[a]}/{len(keep)}"
            )
            print(f"     thesis {fmt_wins(tw[a])}")
        print(f"  B beats A: {ob}/{op} (thesis {tb}/{tp})")
        print(f"  Appendix ratio in [0.8, 1.25]: {inside}/{total} = {inside / max(total, 1):.3f}")
        for data, (median, inside_d, total_d) in per_data(ours, thesis).items():
            print(f"    {data:8s} median ratio {median:.3f}, {inside_d}/{total_d} cells in band")
    if brief:
        print(" | ".join(line))


def write_spec(spec, out, pairs):
    """The spec copy of `--spec` (see the module's doc)."""
    lines = open(spec).read().splitlines()
    keys = [p.split("=", 1) for p in pairs]
    seed = [v for k, v in keys if k.strip() == "map_seed"]
    added = [f"{k.strip()} = {v.strip()}" for k, v in keys if k.strip() != "map_seed"]
    out_lines, section = [], ""
    for line in lines:
        stripped = line.strip()
        if stripped.startswith("["):
            section = stripped.split("]")[0] + "]"
        if section == "[fit]" and stripped.split("=")[0].strip() in ("maps", "pictures"):
            continue
        if section == "[fit.som]" and seed and stripped.startswith("master_seed"):
            line = f"master_seed = {seed[0].strip()}"
        out_lines.append(line)
        if stripped == "[fit]":
            out_lines.extend(["pictures = false"] + added)
    if "[fit]" not in (x.strip() for x in lines):
        sys.exit(f"{spec}: no [fit] section")
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "w") as f:
        f.write("\n".join(out_lines) + "\n")


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(argv) >= 2 else 2
    if argv[1] == "--spec":
        if len(argv) < 4:
            sys.exit(__doc__)
        write_spec(argv[2], argv[3], argv[4:])
        return 0
    brief = "--brief" in argv
    folders = [a for a in argv[1:] if a not in ("--brief", "--spread")]
    if "--spread" in argv:
        spread(folders)
        return 0
    for folder in folders:
        report(folder, brief)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
