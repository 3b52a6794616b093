#!/usr/bin/env python3
"""Check that Cargo.toml's rust-version is at least every locked dependency's rust-version.

clippy's `incompatible_msrv` lint (run by .ci/run with -D warnings) checks our own code against the
same rust-version; this script checks the dependencies, which clippy does not.
Usage: scripts/check_msrv.py   (from the top of the clone; needs cargo on PATH)
"""
import json
import subprocess
import sys


def version(text):
    parts = [int(p) for p in text.split(".")]
    return tuple(parts + [0] * (3 - len(parts)))


host = next(l.split()[1] for l in subprocess.check_output(["rustc", "-vV"], text=True).splitlines() if l.startswith("host:"))
meta = json.loads(subprocess.check_output(["cargo", "metadata", "--format-version", "1", "--locked", "--filter-platform", host]))
ours = next(p for p in meta["packages"] if p["id"] in meta["workspace_members"])
declared = ours.get("rust_version")
if not declared:
    sys.exit("Cargo.toml has no rust-version")
resolved = {n["id"] for n in meta["resolve"]["nodes"]}
needs = sorted(
    ((version(p["rust_version"]), f'{p["name"]} {p["version"]}') for p in meta["packages"]
     if p.get("rust_version") and p["id"] in resolved and p["id"] not in meta["workspace_members"]),
    reverse=True,
)
top, who = needs[0]
if top > version(declared):
    sys.exit(f"Cargo.toml says rust-version {declared}, but {who} needs {'.'.join(map(str, top))}")
print(f"rust-version {declared}: every locked dependency needs at most {'.'.join(map(str, top))} ({who})")
