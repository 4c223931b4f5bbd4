#!/usr/bin/env python3
"""tools/ as tools/README.md describes it.

usage: tools_check.py TOOLS_DIR

- every script in tools/ (*.py, *.sh; lahar_py.py is the shared start-up, not a tool) has a row in
  tools/README.md's table, and every row names a script that exists;
- every Python tool is executable, starts with a #! line, and calls lahar_py.require() before it
  imports h5py, numpy, matplotlib or yaml at the top level (README: "when the python3 on PATH
  lacks h5py/matplotlib they re-run themselves under /usr/bin/python3");
- `TOOL --help` exits 0 for every Python tool (run with this interpreter).
Exit 0 when all hold, 1 with one line per problem.
"""
import os
import re
import subprocess
import sys

THIRD_PARTY = ("h5py", "numpy", "matplotlib", "yaml")


def main():
    if len(sys.argv) != 2:
        print("usage: tools_check.py TOOLS_DIR", file=sys.stderr)
        return 2
    tools = sys.argv[1]
    readme = open(os.path.join(tools, "README.md")).read()
    rows = set(re.findall(r"^\| `([\w.]+\.(?:py|sh))[ `]", readme, re.M))
    scripts = sorted(f for f in os.listdir(tools) if f.endswith((".py", ".sh")) and f != "lahar_py.py")
    problems = []
    for f in scripts:
        if f not in rows:
            problems.append(f"tools/{f}: no row in tools/README.md")
    for f in sorted(rows - set(scripts)):
        problems.append(f"tools/README.md: a row for {f}, which is not in tools/")
    for f in scripts:
        path = os.path.join(tools, f)
        text = open(path).read()
        if not text.startswith("#!"):
            problems.append(f"tools/{f}: no #! line")
        if not os.access(path, os.X_OK):
            problems.append(f"tools/{f}: not executable (README: run them as tools/NAME.py)")
        if not f.endswith(".py"):
            continue
        require = re.search(r"^lahar_py\.require\(", text, re.M)
        for m in re.finditer(r"^(?:import|from) (\w+)", text, re.M):
            if m.group(1) in THIRD_PARTY and (not require or require.start() > m.start()):
                line = text.count("\n", 0, m.start()) + 1
                problems.append(f"tools/{f}:{line}: imports {m.group(1)} before lahar_py.require()")
                break
        r = subprocess.run([sys.executable, path, "--help"], capture_output=True, text=True, timeout=60)
        if r.returncode != 0 or not r.stdout.strip():
            problems.append(f"tools/{f} --help: exit {r.returncode}, {len(r.stdout)} bytes on stdout "
                            f"{r.stderr.strip()[-200:]}")
    for p in problems:
        print(p)
    print(f"tools_check: {len(scripts)} scripts, {len(rows)} README rows: "
          f"{'ok' if not problems else str(len(problems)) + ' problems'}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
