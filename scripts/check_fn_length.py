#!/usr/bin/env python3
"""Fails (exit 1) when a function outside test code is longer than the limit (default 120 lines).

    python3 scripts/check_fn_length.py [LIMIT]

A function runs from its `fn` line to the closing brace at the same indentation; code after a
`#[cfg(test)]` line counts as test code (the unit tests sit at the end of each file).
"""
import os
import re
import sys

LIMIT = int(sys.argv[1]) if len(sys.argv) > 1 else 120
FN = re.compile(r'(\s*)(pub(\([a-z]+\))? )?(const )?(unsafe )?(extern "C" )?fn (\w+)')
too_long = []
for root, _, files in os.walk("src"):
    for name in sorted(files):
        if not name.endswith(".rs") or name.endswith("_tests.rs"):
            continue
        path = os.path.join(root, name)
        lines = open(path, encoding="utf-8").read().split("\n")
        test_from = next((i for i, l in enumerate(lines) if l.strip() == "#[cfg(test)]"), len(lines))
        for i, line in enumerate(lines[:test_from]):
            m = FN.match(line)
            if not m or line.rstrip().endswith(";"):
                continue
            indent = m.group(1)
            end = next((j for j in range(i + 1, len(lines)) if lines[j] == indent + "}"), i)
            if end - i + 1 > LIMIT:
                too_long.append(f"{path}:{i + 1}: fn {m.group(7)} is {end - i + 1} lines (limit {LIMIT})")
for t in too_long:
    print(t)
print(f"check_fn_length: {len(too_long)} function(s) over {LIMIT} lines outside tests")
sys.exit(1 if too_long else 0)
