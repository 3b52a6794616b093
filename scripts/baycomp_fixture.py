"""Write tests/fixtures/baycomp_signed_rank.csv: inputs and baycomp's Bayesian signed-rank
probabilities, the reference for src/stats/bayes.rs. Run: python3 scripts/baycomp_fixture.py
(it makes target/baycomp-venv with baycomp pinned and runs itself there when baycomp is missing).

Columns: name, a, b (';'-separated paired errors), rope, and baycomp's SignedRankTest.probs(x=a,
y=b, rope, nsamples=50000) as p_left, p_rope, p_right (p_rope = 0 when rope = 0)."""

import os
import subprocess
import sys
from pathlib import Path

BAYCOMP = "1.0.3"
ROOT = Path(__file__).resolve().parent.parent

try:
    import baycomp
    import numpy as np
except ImportError:
    if os.environ.get("BAYCOMP_FIXTURE_CHILD"):
        raise
    venv = ROOT / "target" / "baycomp-venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    subprocess.run([str(venv / "bin" / "pip"), "install", "--quiet", "--disable-pip-version-check", f"baycomp=={BAYCOMP}"], check=True)
    env = dict(os.environ, BAYCOMP_FIXTURE_CHILD="1")
    sys.exit(subprocess.run([str(venv / "bin" / "python"), __file__], env=env).returncode)


def cases():
    rng = np.random.default_rng(20260)
    base = rng.uniform(10, 30, 30)
    yield "clear_a_better", base[:10], base[:10] + rng.uniform(0.5, 1.5, 10), 0.0
    yield "close_no_rope", base[:12], base[:12] + rng.normal(0.05, 0.3, 12), 0.0
    yield "close_with_rope", base[:12], base[:12] + rng.normal(0.05, 0.3, 12), 0.1
    yield "mostly_rope", base[:15], base[:15] + rng.normal(0.0, 0.02, 15), 0.1
    yield "b_better_rope", base[:8], base[:8] - rng.uniform(0.0, 0.4, 8), 0.05
    ties = np.array([1.0, 2.0, 2.0, 3.0, 5.0, 5.0])
    yield "ties_and_zeros", ties, ties + np.array([0.0, 0.5, -0.5, 0.0, 0.25, -0.25]), 0.0
    yield "walsh_on_rope_edge", ties, ties + np.array([0.25, 0.25, -0.25, 0.75, 0.0, 0.5]), 0.25
    yield "thirty_mixed", base, base + rng.normal(0.1, 0.5, 30), 0.2
    small = rng.uniform(22.5, 22.6, 20)
    yield "error_scale", small, small + rng.normal(2e-6, 4e-6, 20), 1e-6
    yield "n_three", np.array([1.0, 2.0, 3.0]), np.array([1.5, 1.9, 3.4]), 0.0


def main():
    out = ROOT / "tests" / "fixtures" / "baycomp_signed_rank.csv"
    lines = ["name,a,b,rope,p_left,p_rope,p_right"]
    for k, (name, a, b, rope) in enumerate(cases()):
        p = baycomp.SignedRankTest.probs(a, b, rope, nsamples=50000, random_state=1000 + k)
        left, mid, right = (p[0], 0.0, p[1]) if rope == 0 else p
        fmt = lambda v: ";".join(repr(float(x)) for x in v)
        lines.append(f"{name},{fmt(a)},{fmt(b)},{rope!r},{left:.5f},{mid:.5f},{right:.5f}")
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out} with baycomp {baycomp.__version__ if hasattr(baycomp, '__version__') else BAYCOMP}: {len(lines) - 1} cases")


main()
