#!/usr/bin/env python3
"""What `lahar keys` tells a user, checked against the cases they read.

usage: case_keys_doc.py LAHAR CASES_DIR

- every key line of `lahar keys --yaml` has a default (a value, "(required)" or "(none)") and a
  description, and the description's parentheses are balanced (a description cut in the middle of
  a parenthesis was how a lost half showed);
- `lahar keys SECTION` works for every section of the reference and lists the same keys;
- every key written in cases/*.yaml is one `lahar keys` lists for its section (the sub-mappings
  that are no section of their own, e.g. bodies[].orientation or check.metrics, are not walked).
Exit 0 when all hold, 1 with one line per problem.
"""
import glob
import os
import re
import subprocess
import sys

import yaml


def reference(lahar):
    """{section path: {key: (default, rest of the line)}} from `lahar keys --yaml`."""
    out = subprocess.run([lahar, "keys", "--yaml"], check=True, capture_output=True, text=True).stdout
    sections, cur = {}, None
    for line in out.splitlines():
        m = re.match(r"^# --- (.*?): ", line)
        if m:
            cur = "" if m.group(1) == "top level" else m.group(1)
            sections[cur] = {}
            continue
        m = re.match(r"^# +(\w+): (.*?)\s+# (.*)$", line)
        if m and cur is not None and m.group(3) != "a list; each item:":
            sections[cur][m.group(1)] = (m.group(2), m.group(3))
    return sections


def balanced(text):
    # intervals such as "in (0, 1]" or "[lo, hi)" are not parentheses
    text = re.sub(r"[\[(][^\[\]()]*,[^\[\]()]*[\])]", "", text)
    depth = 0
    for ch in text:
        depth += (ch == "(") - (ch == ")")
        if depth < 0:
            return False
    return depth == 0


def check_table(lahar, sections, problems):
    for path, keys in sections.items():
        if not keys:
            problems.append(f"lahar keys --yaml: section '{path or 'top level'}' lists no keys")
        for name, (default, rest) in keys.items():
            where = f"lahar keys: {path + '.' if path else ''}{name}"
            if not default:
                problems.append(f"{where}: no default")
            # rest = [unit; ][allowed; ]description: the description is what follows the last "; "
            # outside parentheses
            desc, depth, start = rest, 0, 0
            for i, ch in enumerate(rest):
                depth += (ch == "(") - (ch == ")")
                if depth == 0 and rest[i:i + 2] == "; ":
                    start = i + 2
            desc = rest[start:]
            if len(desc.strip()) < 3:
                problems.append(f"{where}: no description ('{rest}')")
            if not balanced(rest):
                problems.append(f"{where}: unbalanced parentheses, the description is cut: '{rest}'")
        if path:
            r = subprocess.run([lahar, "keys", path], capture_output=True, text=True)
            if r.returncode != 0:
                problems.append(f"lahar keys {path}: exit {r.returncode}: {r.stderr.strip()}")
                continue
            listed = {ln.split()[0] for ln in r.stdout.splitlines()[2:] if ln.strip()}
            if listed != set(keys):
                problems.append(f"lahar keys {path}: lists {sorted(listed)}, --yaml {sorted(keys)}")


def walk(node, path, sections, where, problems):
    """Check the keys of the mapping `node` that belongs to section `path`."""
    if not isinstance(node, dict):
        return
    known = sections.get(path, {})
    for key, value in node.items():
        if key not in known:
            problems.append(f"{where}: key '{key}' of section '{path or 'top level'}' is not in `lahar keys`")
            continue
        sub = f"{path}.{key}" if path else key
        if path == "" and key == "materials" and isinstance(value, dict):
            for name, mat in value.items():
                walk(mat, "materials.NAME", sections, where, problems)
        elif f"{sub}[]" in sections and isinstance(value, list):
            for item in value:
                walk(item, f"{sub}[]", sections, where, problems)
        elif sub in sections and isinstance(value, dict):
            walk(value, sub, sections, where, problems)


def main():
    if len(sys.argv) != 3:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    lahar, cases = sys.argv[1], sys.argv[2]
    problems = []
    sections = reference(lahar)
    check_table(lahar, sections, problems)
    files = sorted(f for f in glob.glob(os.path.join(cases, "*.yaml")) if os.path.basename(f) != "reference.yaml")
    for f in files:
        with open(f) as fh:
            walk(yaml.safe_load(fh), "", sections, f, problems)
    for p in problems:
        print(p)
    nkeys = sum(len(k) for k in sections.values())
    print(f"case_keys_doc: {len(sections)} sections, {nkeys} keys, {len(files)} cases: "
          f"{'ok' if not problems else str(len(problems)) + ' problems'}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
