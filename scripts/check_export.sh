#!/usr/bin/env bash
# `somnurbs export` read by a real IGES reader (issue 47): gmsh from the package index (its
# OpenCASCADE IGES reader), in a virtual environment, loads the optimised talus net of a finished
# Chapter 6 folder, exported in the map's frame and in the scan's own, and
# scripts/check_export_gmsh.py checks that its surface error at the data parameters is the
# record's and that the net lies on the scan in the scan's frame.
# Usage: scripts/check_export.sh RESULTS_CH6_FOLDER   (e.g. results/thesis_quick/ch6_same)
# Environment: EXPORT_VENV (default target/export-venv), PYTHON (python3).
set -euo pipefail
cd "$(dirname "$0")/.."
results="$1"
venv="${EXPORT_VENV:-target/export-venv}"
python="${PYTHON:-python3}"
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import gmsh" 2>/dev/null; then
  "$python" -m venv "$venv"
  "$venv/bin/pip" install --quiet "gmsh==4.15.2"
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cell="$(awk -F, 'NR==1{for(i=1;i<=NF;i++)h[$i]=i; next} $h["dataset"]=="talus" && $h["optimiser"]=="de" && $h["cn_x"]==18 {print $h["cell"]; exit}' "$results/runs.csv")"
[ -n "$cell" ] || { echo "no DE cell on the talus at 18x18 in $results/runs.csv"; exit 1; }
for frame in normalised data; do
  cargo run --release --quiet -- export "$results" --cell "$cell" --frame "$frame" --out "$work/$frame"
  "$venv/bin/python" scripts/check_export_gmsh.py "$work/$frame"
done
