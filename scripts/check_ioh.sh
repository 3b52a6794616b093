#!/usr/bin/env bash
# Check that iohinspector (the IOHprofiler group's Python loader, version pinned below) loads every
# run of a Chapter 6 results folder's IOHprofiler export with the evaluation counts and final best
# values of its runs.csv (scripts/check_ioh.py). Makes a virtual environment on first use.
# Usage: scripts/check_ioh.sh [RESULTS_FOLDER]   (default results/thesis_quick/ch6_same)
# Environment: CHECK_IOH_VENV (default target/check-ioh-venv), PYTHON (default python3).
set -euo pipefail
cd "$(dirname "$0")/.."
IOHINSPECTOR_VERSION=0.0.8
folder="${1:-results/thesis_quick/ch6_same}"
venv="${CHECK_IOH_VENV:-target/check-ioh-venv}"
if ! "$venv/bin/python" -c "import iohinspector, importlib.metadata as m; assert m.version('iohinspector') == '$IOHINSPECTOR_VERSION'" 2>/dev/null; then
    "${PYTHON:-python3}" -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check "iohinspector==$IOHINSPECTOR_VERSION"
fi
exec "$venv/bin/python" scripts/check_ioh.py "$folder"
