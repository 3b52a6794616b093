#!/usr/bin/env python3
"""Fails (exit 1) when README.md or docs/**/*.md cite a path or a code item that does not exist.

    python3 scripts/check_docs.py

What it checks, naming file:line for each failure:
- Repository paths in backticks (inline or fenced code) that begin with src/, docs/, scripts/,
  experiments/, tests/, benches/, results/baselines/ or .ci/: the file or folder must exist. A
  placeholder such as <data> or a * matches any name (at least one match must exist); {a,b} is
  expanded.
- Relative links ([text](path#anchor)), resolved from the page's folder: the target must exist,
  and an anchor into a Markdown page must be one of its headings (GitHub's slugs).
- Rust items cited as `module::...::Item` paths that begin with a crate module (e.g.
  `optim::REGISTRY`, `experiment::family::Section`): the last segment must be defined
  (fn|struct|enum|const|static|trait|type|mod|macro_rules! NAME) in the file or folder under src/
  the leading segments name.
"""
import glob
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PREFIXES = ("src/", "docs/", "scripts/", "experiments/", "tests/", "benches/",
            "results/baselines/", ".ci/")
INLINE = re.compile(r"`([^`\n]+(?:\n[^`\n]+)?)`")
LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
ITEM = re.compile(r"^(?:crate::)?((?:[a-z_][a-z0-9_]*::)+)([A-Za-z_][A-Za-z0-9_]*)(?:\(\)|!)?$")
TRAIL = ".,;:()[]'\"`"


def crate_modules():
    """The top-level modules of the crate: src/<name>.rs and src/<name>/ (but main and lib)."""
    names = set()
    for entry in os.listdir(os.path.join(ROOT, "src")):
        name = entry[:-3] if entry.endswith(".rs") else entry
        if name not in ("main", "lib"):
            names.add(name)
    return names


def pages():
    found = [os.path.join(ROOT, "README.md")]
    found += sorted(glob.glob(os.path.join(ROOT, "docs", "**", "*.md"), recursive=True))
    return [p for p in found if os.path.isfile(p)]


def expand_braces(text):
    m = re.search(r"\{([^{}]*,[^{}]*)\}", text)
    if not m:
        return [text]
    out = []
    for alt in m.group(1).split(","):
        out += expand_braces(text[: m.start()] + alt + text[m.end():])
    return out


def path_exists(rel):
    rel = rel.rstrip("/")
    for variant in expand_braces(rel):
        pattern = re.sub(r"<[^>]*>", "*", variant)
        if any(c in pattern for c in "*?["):
            if not glob.glob(os.path.join(ROOT, pattern)):
                return False
        elif not os.path.exists(os.path.join(ROOT, pattern)):
            return False
    return True


def slug(heading):
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def anchors(md_path):
    found, seen = set(), {}
    in_fence = False
    for line in open(md_path, encoding="utf-8"):
        if line.lstrip().startswith("```"):
            in_fence = not in_fence
            continue
        m = None if in_fence else re.match(r"#{1,6}\s+(.*)", line)
        if m:
            base = slug(m.group(1))
            n = seen.get(base, 0)
            seen[base] = n + 1
            found.add(base if n == 0 else f"{base}-{n}")
    return found


def item_defined(segments, name):
    """Whether NAME is defined in the file or folder under src/ that `segments` lead to."""
    where = os.path.join(ROOT, "src")
    for seg in segments:
        if os.path.isdir(os.path.join(where, seg)):
            where = os.path.join(where, seg)
        elif os.path.isfile(os.path.join(where, seg + ".rs")):
            where = os.path.join(where, seg + ".rs")
            break  # later segments are inline modules or types of that file
        else:
            return False
    if os.path.isdir(where):
        if os.path.isfile(os.path.join(where, name + ".rs")) or os.path.isdir(
            os.path.join(where, name)
        ):
            return True
        files = glob.glob(os.path.join(where, "**", "*.rs"), recursive=True)
    else:
        files = [where]
    definition = re.compile(
        r"\b(?:fn|struct|enum|const|static|trait|type|mod|macro_rules!)\s+" + re.escape(name) + r"\b"
    )
    return any(definition.search(open(f, encoding="utf-8").read()) for f in files)


def check_page(path, modules, failures, counts):
    rel_page = os.path.relpath(path, ROOT)
    lines = open(path, encoding="utf-8").read().split("\n")
    prose, fenced = [], []
    in_fence = False
    for n, line in enumerate(lines, 1):
        if line.lstrip().startswith("```"):
            in_fence = not in_fence
            prose.append("")
            continue
        if in_fence:
            fenced.append((n, line))
            prose.append("")
        else:
            prose.append(line)
    text = "\n".join(prose)

    def line_of(pos):
        return text.count("\n", 0, pos) + 1

    def check_token(token, n):
        token = token.strip(TRAIL)
        if token.startswith("./"):
            token = token[2:]
        if token.startswith(PREFIXES):
            counts["paths"] += 1
            if not path_exists(token):
                failures.append(f"{rel_page}:{n}: path `{token}` does not exist")

    for m in INLINE.finditer(text):
        span, n = m.group(1).replace("\n", " "), line_of(m.start())
        item = ITEM.match(span.strip())
        if item:
            segments = item.group(1).split("::")[:-1]
            if segments[0] in modules:
                counts["items"] += 1
                if not item_defined(segments, item.group(2)):
                    failures.append(f"{rel_page}:{n}: code item `{span.strip()}` is not defined "
                                    f"under src/{'/'.join(segments)}")
            continue
        for token in re.split(r"[\s=,]+", span):
            check_token(token, n)
    for n, line in fenced:
        for token in re.split(r"[\s=,]+", line):
            check_token(token, n)
    for m in LINK.finditer(text):
        target, n = m.group(1), line_of(m.start())
        if re.match(r"[a-z]+:", target) or target.startswith("#") and not target[1:]:
            continue
        counts["links"] += 1
        file_part, _, anchor = target.partition("#")
        dest = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) if file_part else path
        if not os.path.exists(dest):
            failures.append(f"{rel_page}:{n}: link `{target}` does not exist")
        elif anchor and dest.endswith(".md") and anchor not in anchors(dest):
            failures.append(f"{rel_page}:{n}: link `{target}`: no heading with that anchor")


def main():
    modules = crate_modules()
    failures, counts = [], {"paths": 0, "items": 0, "links": 0}
    checked = pages()
    for page in checked:
        check_page(page, modules, failures, counts)
    for failure in failures:
        print(failure)
    summary = (f"{len(checked)} pages, {counts['paths']} paths, {counts['links']} links, "
               f"{counts['items']} code items")
    if failures:
        print(f"check_docs: {len(failures)} broken citation(s) in {summary}")
        sys.exit(1)
    print(f"check_docs: {summary}: all exist")


if __name__ == "__main__":
    main()
