#!/usr/bin/env bash
# Build the Python package's standalone wheel (issue 50): abi3 (CPython 3.9 and newer), tagged
# manylinux_2_17 (linked by zig against glibc 2.17's symbols, so any x86-64 Linux from 2014 on
# loads it), with the shipped specs inside the extension. Checked with `auditwheel show`: the
# script fails unless the wheel is manylinux-compliant and needs no library outside the policy.
#
#   scripts/build_wheel.sh [OUT_DIR]      # default target/wheels; prints the wheel's path last
#
# Environment: PYTHON (python3), WHEEL_VENV (the build tools' venv, default target/wheel-venv:
# maturin and ziglang from PyPI, auditwheel).
set -euo pipefail
cd "$(dirname "$0")/.."
MATURIN_VERSION=1.16.0 ZIG_VERSION=0.17.1 AUDITWHEEL_VERSION=6.8.2
out="${1:-target/wheels}"
venv="${WHEEL_VENV:-target/wheel-venv}"
if [ ! -x "$venv/bin/maturin" ]; then
    "${PYTHON:-python3}" -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check \
        "maturin==$MATURIN_VERSION" "ziglang==$ZIG_VERSION" "auditwheel==$AUDITWHEEL_VERSION"
fi
rm -rf "$out"
mkdir -p "$out"
PATH="$venv/bin:$PATH" maturin build --release --strip --zig --compatibility manylinux2014 \
    -m python/Cargo.toml -o "$out" >&2
wheel="$(ls "$out"/somnurbs-*.whl)"
case "$wheel" in
    *manylinux_2_17_x86_64*) ;;
    *) echo "build_wheel: $wheel is not tagged manylinux_2_17" >&2; exit 1 ;;
esac
shown="$("$venv/bin/auditwheel" show "$wheel" 2>&1)"
echo "$shown" >&2
echo "$shown" | tr '\n' ' ' | grep -q 'is consistent with the following platform tag: *"manylinux_2_17_x86_64"' \
    || { echo "build_wheel: auditwheel does not find $wheel manylinux_2_17-consistent" >&2; exit 1; }
echo "$wheel"
