#!/usr/bin/python3
"""Run a case against an experiment or a reference solution at CI resolution and check it with its
comparison tool.

  experiment_check.py LAHAR OUT CASE.yaml TOOL [PATH=VALUE ...] [-- TOOL BOUNDS ...]

Writes CASE with the overrides (tools/case_override.py syntax, e.g. sph.dx=0.01 time.end=0.45) to
OUT, runs it on one thread in one process, then tools/TOOL --check with the bounds after "--".
TOOL is compare_lobovsky.py (Lobovsky et al. 2014; bounds --rise-tol, --peak-band, --level-tol,
--spread-tol), compare_spheric2.py (SPHERIC Test 2, Kleefsman et al. 2005; bounds --impact-tol,
--travel-tol, --level-tol, --p1-mean-band) compare_bore.py (the bore a wall reflects, against
the shallow-water shock; bounds --speed-tol, --force-tol, --depth-tol) or compare_jet.py (a jet
hitting a wall, against the free-streamline solution; bounds --pressure-tol, --force-tol); each tool's header says
what it measures. The bounds used and the values they guard: tests/dam_break_impact.cmake,
cases/README.md. Writes OUT/NAME.json and OUT/NAME.png (NAME: the tool's name without compare_ and
.py)."""
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
TOOLS = os.path.join(HERE, "..", "tools")
sys.path.insert(0, TOOLS)
import lahar_py  # noqa: E402

lahar_py.require("yaml")
import case_override  # noqa: E402


def main():
    args = sys.argv[1:]
    bounds = []
    if "--" in args:
        k = args.index("--")
        args, bounds = args[:k], args[k + 1:]
    if len(args) < 4:
        print(__doc__)
        return 2
    lahar, out, case, tool, overrides = args[0], args[1], args[2], args[3], args[4:]
    name = tool.replace("compare_", "").replace(".py", "")
    os.makedirs(out, exist_ok=True)
    yml = os.path.join(out, os.path.basename(case))
    if case_override.main(["case_override.py", case, yml] + overrides):
        return 2
    run = os.path.join(out, "run")
    r = subprocess.run([lahar, "run", yml, "-o", run, "--in-process", "--threads", "1", "-q", "--overwrite"])
    if r.returncode != 0:
        print(f"experiment_check: lahar run {yml} exited {r.returncode}")
        return 1
    return subprocess.run([sys.executable, os.path.join(TOOLS, tool), run, "--check",
                           "-o", os.path.join(out, name + ".png"), "--json", os.path.join(out, name + ".json")]
                          + bounds).returncode


if __name__ == "__main__":
    sys.exit(main())
