#!/usr/bin/env bash
# somnurbs beside its Python peers, in one run on this machine (issue 21's check): the bench's
# control-net problem (18x18 net on the spindle's 20x20 DNSOM map) is exported, a numpy fitness
# written independently (scripts/peers/peers.py) must give somnurbs' value to 1e-12 relative,
# then one core each: the fitness, DE, PSO and cuckoo-search runs of `cargo bench --bench optim`
# beside numpy (one call and 40 per call), scipy's differential_evolution (per individual and
# vectorised) and numpy DE, PSO and cuckoo search, as a Markdown table with the CPU model.
#
#   scripts/bench_peers.sh [OUT_DIR]      (default: a temporary folder)
#
# Environment: PEERS_GENERATIONS (default 2000, the thesis' budget; CI uses a few), PEERS_VENV
# (default target/peers-venv, made on first use), PYTHON (default python3), SOMNURBS_DATA;
# PEERS_PROTOCOL=1 then also times the full Chapter 6 protocol (scripts/bench_ch6_protocol.sh,
# about 12 minutes on 2 cores; PREV_BIN as there), so that every figure of issue 21 comes from
# one run on one machine.
set -euo pipefail
cd "$(dirname "$0")/.."
NUMPY_VERSION=2.2.6
SCIPY_VERSION=1.15.3
out="${1:-$(mktemp -d)}"
gens="${PEERS_GENERATIONS:-2000}"
venv="${PEERS_VENV:-target/peers-venv}"
mkdir -p "$out"
if ! "$venv/bin/python" -c "import numpy, scipy; assert (numpy.__version__, scipy.__version__) == ('$NUMPY_VERSION', '$SCIPY_VERSION')" 2>/dev/null; then
    "${PYTHON:-python3}" -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check "numpy==$NUMPY_VERSION" "scipy==$SCIPY_VERSION"
fi
# One core for everyone: our bench runs on one thread, so the peers' BLAS does too.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
BENCH_EXPORT="$out/problem.json" cargo bench --quiet --bench optim > /dev/null
BENCH_ONLY=de,pso,csa,icsa BENCH_GENERATIONS="$gens" cargo bench --quiet --bench optim | tee "$out/somnurbs.txt"
"$venv/bin/python" scripts/peers/peers.py "$out/problem.json" "$out/somnurbs.txt" "$gens" | tee "$out/peers.md"
if [ "${PEERS_PROTOCOL:-0}" = 1 ]; then
    scripts/bench_ch6_protocol.sh "$out/protocol" | tee "$out/protocol.txt"
fi
