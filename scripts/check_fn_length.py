#!/usr/bin/env python3
"""Fails (exit 1) when a function outside test code is longer than the limit (default 120 lines).

    python3 scripts/check_fn_length.py [LIMIT]

A function runs from its `fn` line to the closing brace at the same indentation. Test code is
what a `#[cfg(test)]` attribute marks: the item right after it (a `mod tests { ... }`, a
function), up to its closing brace at the same indentation; code after a test module is checked.
"""
import os
import re
import sys

LIMIT = int(sys.argv[1]) if len(sys.argv) > 1 else 120
FN = re.compile(r'(\s*)(pub(\([a-z]+\))? )?(const )?(unsafe )?(extern "C" )?fn (\w+)')
too_long = []


def test_lines(lines):
    """Which lines belong to an item a `#[cfg(test)]` attribute marks (the attribute included)."""
    marked = [False] * len(lines)
    i = 0
    while i < len(lines):
        if lines[i].strip() != "#[cfg(test)]":
            i += 1
            continue
        indent = lines[i][: len(lines[i]) - len(lines[i].lstrip())]
        j = i + 1
        while j < len(lines) and lines[j].strip().startswith("#["):
            j += 1
        if j < len(lines) and lines[j].rstrip().endswith(";"):
            end = j  # `mod tests;` or a one-line item
        else:
            end = next((k for k in range(j + 1, len(lines)) if lines[k] == indent + "}"), len(lines) - 1)
        for k in range(i, end + 1):
            marked[k] = True
        i = end + 1
    return marked


for root, _, files in os.walk("src"):
    for name in sorted(files):
        if not name.endswith(".rs") or name.endswith("_tests.rs"):
            continue
        path = os.path.join(root, name)
        lines = open(path, encoding="utf-8").read().split("\n")
        in_test = test_lines(lines)
        for i, line in enumerate(lines):
            if in_test[i]:
                continue
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
