#!/usr/bin/env bash
# The check of the Python package (python/): build its standalone wheel (scripts/build_wheel.sh:
# abi3, manylinux_2_17, checked by auditwheel), install it into a fresh virtual environment in a
# folder outside the clone (no clone, no Rust there), run its pytest tests from that folder
# against the CLI (python/tests/, copied out; the shipped specs come from inside the wheel), run
# the worked example
# (pycma's CMA-ES and scipy's DE on ch6_exact --profile quick, logged with ioh) at a small budget,
# load its logs with iohinspector and compare them beside a somnurbs Chapter 6 folder.
#
#   scripts/check_python.sh [CH6_EXACT_FOLDER] [BENCH_EXPORT_JSON]
#
# CH6_EXACT_FOLDER: a finished `somnurbs run experiments/ch6_exact.toml --profile quick` (CI: the
# quick reproduction's); without it one is run into the work folder. BENCH_EXPORT_JSON: what
# `BENCH_EXPORT=FILE cargo bench --bench optim` wrote (CI: the peers check's); without it the test
# of the fitness at a perturbed point against the Rust bench is skipped. Environment:
# PYTHON_CHECK_DIR (work folder, default target/python-check, emptied first), PYTHON (python3),
# PYTHON_ELSEWHERE (the folder outside the clone for the venv and the tests, default a new
# temporary folder, removed at the end),
# CHECK_IOH_VENV (iohinspector's, made by scripts/check_ioh.sh; default target/check-ioh-venv),
# EXAMPLE_EVALUATIONS (default 4040 per run, the documented example; at that budget the tables in README.md and docs/python.md must be what example_table.py makes of the outputs). Uses the somnurbs binary of CARGO_TARGET_DIR (or
# target/), built first.
set -euo pipefail
cd "$(dirname "$0")/.."
NUMPY_VERSION=2.2.6 SCIPY_VERSION=1.15.3 IOH_VERSION=0.4.2 CMA_VERSION=4.5.0 PYTEST_VERSION=9.2.0
work="${PYTHON_CHECK_DIR:-target/python-check}"
rm -rf "$work"
mkdir -p "$work"
work="$(cd "$work" && pwd)"
target="${CARGO_TARGET_DIR:-target}"
cargo build --release --quiet
export SOMNURBS_BIN="$(cd "$target/release" && pwd)/somnurbs"
clone="$(pwd)"
echo "-- the wheel (scripts/build_wheel.sh)"
wheel="$(scripts/build_wheel.sh "$work/wheels" | tail -1)"
elsewhere="${PYTHON_ELSEWHERE:-$(mktemp -d)}"
[ -n "${PYTHON_ELSEWHERE:-}" ] || trap 'rm -rf "$elsewhere"' EXIT
case "$(cd "$elsewhere" && pwd)/" in "$clone"/*) echo "PYTHON_ELSEWHERE is inside the clone"; exit 1 ;; esac
venv="$elsewhere/venv"
"${PYTHON:-python3}" -m venv "$venv"
pip=("$venv/bin/pip" install --quiet --disable-pip-version-check)
"${pip[@]}" "numpy==$NUMPY_VERSION" "scipy==$SCIPY_VERSION" "ioh==$IOH_VERSION" "cma==$CMA_VERSION" "pytest==$PYTEST_VERSION"
echo "-- pip install $(basename "$wheel") (fresh venv in $elsewhere, $("$venv/bin/python" --version))"
"${pip[@]}" "$wheel"
(cd "$elsewhere" && "$venv/bin/python" -c "import somnurbs; print('somnurbs', somnurbs.__version__, 'from', somnurbs.__file__)")
cp -r python/tests "$elsewhere/tests"
export SOMNURBS_CLONE="$clone" SOMNURBS_DATA="${SOMNURBS_DATA:-$clone/data}"
echo "-- pytest tests (copied to $elsewhere; the installed wheel, the CLI of the clone)"
export SOMNURBS_REQUIRE_ALL=1
if [ -n "${2:-}" ]; then
    SOMNURBS_BENCH_EXPORT="$(cd "$(dirname "$2")" && pwd)/$(basename "$2")"
    export SOMNURBS_BENCH_EXPORT
else
    export SOMNURBS_REQUIRE_ALL=0
fi
(cd "$elsewhere" && "$venv/bin/python" -m pytest -q -p no:cacheprovider tests)
echo "-- the worked example at ${EXAMPLE_EVALUATIONS:-4040} evaluations per run"
"$venv/bin/python" python/examples/external_optimisers.py --out "$work/ioh_external" --evaluations "${EXAMPLE_EVALUATIONS:-4040}"
folder="${1:-}"
if [ -z "$folder" ]; then
    folder="$work/ch6_exact"
    "$SOMNURBS_BIN" run experiments/ch6_exact.toml --profile quick --out "$folder" >/dev/null
fi
echo "-- iohinspector loads the example's logs"
ioh_venv="${CHECK_IOH_VENV:-target/check-ioh-venv}"
"$ioh_venv/bin/python" scripts/check_python_ioh.py "$work/ioh_external" 3 "${EXAMPLE_EVALUATIONS:-4040}"
echo "-- somnurbs compare $folder --external (the example's optimisers beside GA, DE and PSO)"
"$SOMNURBS_BIN" compare "$folder" --external "$work/ioh_external" --out "$work/compare" > "$work/compare.txt"
grep -E "mean rank|AOCC" "$work/compare.txt"
for o in cma-es scipy-de; do
    grep -q "^all,$o," "$work/compare/compare_aocc.csv" || { echo "compare_aocc.csv has no $o"; exit 1; }
done
if [ "${EXAMPLE_EVALUATIONS:-4040}" = 4040 ]; then
    echo "-- the docs' tables are the example's (python/examples/example_table.py --check)"
    "$venv/bin/python" python/examples/example_table.py "$folder" "$work/ioh_external" "$work/compare" --check README.md docs/python.md
fi
