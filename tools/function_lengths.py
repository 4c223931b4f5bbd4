#!/usr/bin/env python3
"""The longest C functions of the tree: a readability measure (docs/bench/structure.md).

usage: function_lengths.py [--top N] [--min LINES] [--with-tests] [--rev REV] [ROOT]

A function is counted from its opening brace at column 0 to the closing brace at column 0 (lahar's
layout: every function body opens and closes in the first column), so the count is the lines of
its body. Files are the tracked *.c files of the git tree at ROOT (default: this checkout), or of
revision REV (`--rev a40b60a`) without checking it out. Tests (tests/) are left out unless
--with-tests. Prints a Markdown table, longest first, then the count above --min (default 80).
"""
import argparse
import os
import re
import subprocess
import sys


def tracked_sources(root, rev):
    if rev:
        out = subprocess.check_output(["git", "-C", root, "ls-tree", "-r", "--name-only", rev], text=True)
    else:
        out = subprocess.check_output(["git", "-C", root, "ls-files"], text=True)
    return [f for f in out.split() if f.endswith(".c")]


def read_source(root, rev, path):
    if rev:
        return subprocess.check_output(["git", "-C", root, "show", f"{rev}:{path}"], text=True)
    with open(os.path.join(root, path), encoding="utf-8") as f:
        return f.read()


def functions(text):
    """(name, body lines) of each function whose body opens with '{' in column 0."""
    lines = text.split("\n")
    i = 0
    while i < len(lines):
        if lines[i].startswith("{") and i > 0:
            j = i - 1  # the signature: the nearest line above with an opening parenthesis
            while j > 0 and "(" not in lines[j]:
                j -= 1
            m = re.search(r"(\w+)\s*\(", re.sub(r"__attribute__\s*\(\(.*?\)\)", "", lines[j]))
            k = i + 1
            while k < len(lines) and not lines[k].startswith("}"):
                k += 1
            yield (m.group(1) if m else "?"), k - i
            i = k
        i += 1


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("root", nargs="?", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    ap.add_argument("--top", type=int, default=20, help="rows of the table (default 20)")
    ap.add_argument("--min", type=int, default=80, help="count the functions longer than this (default 80)")
    ap.add_argument("--with-tests", action="store_true", help="include tests/")
    ap.add_argument("--rev", help="a git revision to measure instead of the working tree")
    a = ap.parse_args()
    rows = []
    for path in tracked_sources(a.root, a.rev):
        if path.startswith("tests/") and not a.with_tests:
            continue
        for name, n in functions(read_source(a.root, a.rev, path)):
            rows.append((n, path, name))
    rows.sort(key=lambda r: (-r[0], r[1], r[2]))
    print("| lines | function | file |\n|---|---|---|")
    for n, path, name in rows[: a.top]:
        print(f"| {n} | `{name}` | {path} |")
    over = sum(1 for r in rows if r[0] > a.min)
    print(f"\n{len(rows)} functions; {over} longer than {a.min} lines; median "
          f"{sorted(r[0] for r in rows)[len(rows) // 2] if rows else 0}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
