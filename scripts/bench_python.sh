#!/usr/bin/env bash
# Issue 39's speed figure, in one run on this machine: `Problem.f` from Python on a 40-row batch
# beside the Rust bench's fitness (`cargo bench --bench optim`, run before and after the Python
# timings; the faster is the reference) and the numpy fitness of scripts/peers/peers.py, one core
# each (BLAS pinned to one thread), with the CPU model. See docs/python.md.
#
#   scripts/bench_python.sh [OUT_DIR]        (default: a temporary folder)
#
# Environment: BENCH_VENV (default target/py-venv: numpy and the package, installed here with
# `pip install ./python` on first use or when python/ changed), PYTHON (python3).
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-$(mktemp -d)}"
venv="${BENCH_VENV:-target/py-venv}"
mkdir -p "$out"
[ -x "$venv/bin/python" ] || "${PYTHON:-python3}" -m venv "$venv"
"$venv/bin/pip" install --quiet --disable-pip-version-check "numpy==2.2.6" ./python
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
BENCH_EXPORT="$out/problem.json" cargo bench --quiet --bench optim > /dev/null
# The fitness line only: one optimiser for 10 generations after it.
bench() { BENCH_ONLY=de BENCH_GENERATIONS=10 cargo bench --quiet --bench optim > "$1"; }
bench "$out/rust_before.txt"
"$venv/bin/python" python/bench/bench_f.py measure "$out/problem.json" "$out/python.json"
bench "$out/rust_after.txt"
"$venv/bin/python" python/bench/bench_f.py report "$out/python.json" "$out/rust_before.txt" "$out/rust_after.txt" | tee "$out/python.md"
