#!/usr/bin/env python3
"""Every reference to a section of a Markdown file names a section that exists.

usage: doc_section_refs.py SOURCE_DIR

The code, tests, cases and docs point readers at sections as <file>.md "<section>" (e.g.
cases/README.md "Pressure probes"). A reference resolves when FILE.md exists (from the source
root or the referring file's folder; a bare README.md is the referring folder's or the top-level
one) and a heading or a bold paragraph title of it starts with or contains the quoted text (case and
backquotes ignored). Exit 0 when all resolve; 1 with one line per broken reference.
"""
import os
import re
import subprocess
import sys

root = sys.argv[1]
files = subprocess.run(["git", "-C", root, "ls-files"], capture_output=True, text=True, check=True).stdout.split()
REF = re.compile(r'((?:[\w./-]+/)?[\w-]+\.md),? ["“]([^"”\n]{2,80})["”]')
SUFFIXES = (".c", ".h", ".md", ".py", ".sh", ".cmake", ".yaml", ".txt", ".lcm")
titles = {}


def norm(text):
    return text.replace("`", "").lower().strip().rstrip(".")


def sections(path):
    if path not in titles:
        with open(os.path.join(root, path), encoding="utf-8") as fh:
            text = fh.read()
        titles[path] = [norm(re.sub(r"^#+\s*", "", ln)) for ln in text.split("\n") if ln.startswith("#")] + \
            [norm(b) for b in re.findall(r"\*\*([^*]+?)\*\*", text)]
    return titles[path]


def candidates(referrer, ref):
    """The files FILE.md may mean, in order; a bare README.md is the referring folder's or the
    top-level one."""
    here = os.path.dirname(referrer)
    cands = [os.path.join(here, ref), ref] if ref == "README.md" else [ref, os.path.normpath(os.path.join(here, ref))]
    return [c for c in dict.fromkeys(cands) if os.path.isfile(os.path.join(root, c))]


bad, total = [], 0
for f in files:
    if not f.endswith(SUFFIXES) or not os.path.isfile(os.path.join(root, f)):
        continue
    with open(os.path.join(root, f), encoding="utf-8", errors="replace") as fh:
        text = fh.read()
    for m in REF.finditer(text):
        ref, sec = m.group(1), m.group(2)
        line = text.count("\n", 0, m.start()) + 1
        total += 1
        paths = candidates(f, ref)
        if not paths:
            bad.append('%s:%d: %s "%s": no such file' % (f, line, ref, sec))
        elif not any(t.startswith(norm(sec)) or norm(sec) in t for p in paths for t in sections(p)):
            bad.append('%s:%d: %s has no section "%s"' % (f, line, " or ".join(paths), sec))
for b in bad:
    print(b)
print("doc_section_refs: %d references, %d broken" % (total, len(bad)))
sys.exit(1 if bad else 0)
