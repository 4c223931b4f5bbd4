#!/usr/bin/python3
"""tools/h5_compare.py exit status: 0 for identical files, 1 when one float differs by one ulp,
when a dataset is missing, or when a string differs; --exclude skips the differing path.

  tests/test_h5_compare.py WORKDIR"""
import os
import subprocess
import sys

TOOLS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools")
sys.path.insert(0, TOOLS)
import lahar_py  # noqa: E402

lahar_py.require("h5py", "numpy")
import h5py  # noqa: E402
import numpy as np  # noqa: E402


def write(path, tweak=None):
    with h5py.File(path, "w") as f:
        x = np.linspace(0.0, 1.0, 1000).reshape(100, 10)
        if tweak == "ulp":
            x[37, 4] = np.nextafter(x[37, 4], 2.0)
        f["/snapshots/000000/position"] = x
        f["/header/body_name"] = np.array([b"ball", b"floor" if tweak != "name" else b"flour"], dtype=object)
        if tweak != "missing":
            f["/extra"] = np.arange(5, dtype=np.int32)


def run(*args):
    return subprocess.run([sys.executable, os.path.join(TOOLS, "h5_compare.py"), *args, "--quiet"]).returncode


def main():
    d = sys.argv[1]
    os.makedirs(d, exist_ok=True)
    p = {k: os.path.join(d, f"{k}.h5") for k in ("a", "b", "ulp", "missing", "name")}
    write(p["a"])
    write(p["b"])
    for k in ("ulp", "missing", "name"):
        write(p[k], k)
    cases = [((p["a"], p["b"]), 0), ((p["a"], p["ulp"]), 1), ((p["a"], p["missing"]), 1), ((p["a"], p["name"]), 1),
             ((p["a"], p["ulp"], "--exclude", "position$"), 0), ((p["a"], os.path.join(d, "nope.h5")), 2)]
    bad = 0
    for args, want in cases:
        got = run(*args)
        if got != want:
            print(f"FAIL h5_compare {' '.join(os.path.basename(a) for a in args)}: exit {got}, expected {want}")
            bad += 1
    print(f"test_h5_compare: {len(cases) - bad}/{len(cases)} ok")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
