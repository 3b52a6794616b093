"""Speed of ``Problem.f`` from Python beside the Rust bench's fitness, in one run (issue 39).

Usage: python bench_f.py measure PROBLEM_JSON FIGURES_JSON
       python bench_f.py report FIGURES_JSON RUST_BENCH_OUTPUT [RUST_BENCH_OUTPUT_2]

PROBLEM_JSON is the bench's problem (``BENCH_EXPORT=FILE cargo bench --bench optim``: spindle,
20x20 DNSOM map, 18x18 net, chord length: 1740 variables), which is ch6_same's full-profile
problem ``spindle_20x20_18x18_chord_length`` (checked: the same start, the same fitness bit for bit
at B and at a perturbed point). RUST_BENCH_OUTPUT is the text ``cargo bench --bench optim`` printed
(its ``fitness: X us per evaluation`` line and its ``CPU:`` line); scripts/bench_python.sh runs the
bench before and after ``measure``, and the faster of the two is the reference. Times are CPU seconds of the
calling thread, the best of 5 rounds, as the Rust bench measures; the numpy fitness of
scripts/peers/peers.py (the field's way) is timed beside it.
"""

import json
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import somnurbs

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts" / "peers"))
from peers import Problem as NumpyProblem  # noqa: E402

ROUNDS = 5
ROWS = 40


def best_seconds_per_call(f, calls):
    best = float("inf")
    for _ in range(ROUNDS):
        t = time.thread_time()
        for _ in range(calls):
            f()
        best = min(best, (time.thread_time() - t) / calls)
    return best


def rust_figure(path):
    text = Path(path).read_text()
    m = re.search(r"^fitness: ([0-9.]+) us per evaluation", text, re.M)
    if not m:
        sys.exit(f"{path}: no 'fitness: ... us per evaluation' line")
    cpu = re.search(r"^CPU: .*$", text, re.M)
    return float(m.group(1)), cpu.group(0) if cpu else "CPU: unknown"


def lscpu_model():
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        m = re.search(r"^Model name:\s*(.*)$", out, re.M)
        return m.group(1).strip() if m else "unknown"
    except OSError:
        return "unknown (no lscpu)"


def measure(problem_json, out_json):
    """Time the package's and numpy's fitness on the bench's problem; write the figures (us)."""
    doc = json.loads(Path(problem_json).read_text())
    p = next(q for q in somnurbs.problems("ch6_same") if q.name == "spindle_20x20_18x18_chord_length")
    x0, probe = np.array(doc["x0"]), np.array(doc["probe"])
    if not (np.array_equal(p.x0, x0) and p.f(x0) == doc["fitness_x0"] and p.f(probe) == doc["fitness_probe"]):
        sys.exit("bench_f.py: the package's problem is not the bench's")
    rng = np.random.default_rng(1)
    X = np.ascontiguousarray(x0 + rng.uniform(-5e-6, 5e-6, size=(ROWS, p.dimension)))
    x, X1 = X[0].copy(), X[:1].copy()
    npb = NumpyProblem(doc)
    figures = {
        "name": p.name,
        "dimension": p.dimension,
        "batch": best_seconds_per_call(lambda: p.f(X), 5000) * 1e6,
        "single": best_seconds_per_call(lambda: p.f(x), 100000) * 1e6,
        "one_row": best_seconds_per_call(lambda: p.f(X1), 100000) * 1e6,
        "np_batch": best_seconds_per_call(lambda: npb.batch(X), 50) * 1e6,
        "np_single": best_seconds_per_call(lambda: npb.fitness(x), 1000) * 1e6,
        "numpy": np.__version__,
    }
    Path(out_json).write_text(json.dumps(figures))
    return 0


def report(figures_json, rust_outputs):
    """The Markdown table: the package's figures beside the Rust bench's (the faster run)."""
    fig = json.loads(Path(figures_json).read_text())
    rust = [rust_figure(p) for p in rust_outputs]
    rust_us = min(r[0] for r in rust)
    batch, single, one_row = fig["batch"], fig["single"], fig["one_row"]
    per_eval = batch / ROWS
    ratio = per_eval / rust_us
    print(f"CPU (lscpu): {lscpu_model()}; bench's {rust[0][1]}")
    print(f"problem: {fig['name']} of ch6_same (full profile), {fig['dimension']} variables (the bench's)")
    print(f"Rust bench fitness before and after: {', '.join(f'{r[0]:.3f}' for r in rust)} us per evaluation (reference: {rust_us:.3f})")
    print()
    print("| fitness, one core | us per call | us per evaluation | / Rust bench |")
    print("|---|---|---|---|")
    print(f"| Rust bench (`cargo bench --bench optim`) | | {rust_us:.3f} | 1 |")
    print(f"| Python `p.f(X)`, X of {ROWS} rows | {batch:.2f} | {per_eval:.3f} | {ratio:.3f}x |")
    print(f"| Python `p.f(x)`, one point | {single:.3f} | {single:.3f} | {single / rust_us:.3f}x |")
    print(f"| Python `p.f(X)`, X of 1 row | {one_row:.3f} | {one_row:.3f} | {one_row / rust_us:.3f}x |")
    print(f"| numpy {fig['numpy']} (scripts/peers/peers.py), {ROWS} rows per call | {fig['np_batch']:.1f} | {fig['np_batch'] / ROWS:.2f} | {fig['np_batch'] / ROWS / rust_us:.1f}x |")
    print(f"| numpy, one point per call | {fig['np_single']:.1f} | {fig['np_single']:.1f} | {fig['np_single'] / rust_us:.1f}x |")
    print()
    print(f"per-call overhead of p.f: one point {single - rust_us:.3f} us (call minus one Rust evaluation); "
          f"a {ROWS}-row batch {batch - ROWS * rust_us:.2f} us (call minus {ROWS} Rust evaluations)")
    verdict = "within" if ratio <= 1.2 else "NOT within"
    print(f"p.f(X) per evaluation is {ratio:.3f}x the Rust bench's: {verdict} the 1.2x target")
    return 0 if ratio <= 1.2 else 1


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "measure":
        sys.exit(measure(sys.argv[2], sys.argv[3]))
    if len(sys.argv) >= 4 and sys.argv[1] == "report":
        sys.exit(report(sys.argv[2], sys.argv[3:]))
    sys.exit(__doc__)
