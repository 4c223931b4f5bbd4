#!/usr/bin/python3
"""A python reader (h5py, swmr=True) follows OUT/forces.h5 while `test_output_swmr --writer`
appends to it: it must see /t grow at least twice before the writer ends, with rows
t[k] = k * 1e-3, and all 40 rows at the end.

  tests/test_output_swmr_h5py.py PATH/TO/test_output_swmr OUTDIR"""
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
import lahar_py  # noqa: E402

lahar_py.require("h5py", "numpy")
import h5py  # noqa: E402
import numpy as np  # noqa: E402


def main():
    exe, out = sys.argv[1], sys.argv[2]
    path = os.path.join(out, "forces.h5")
    if os.path.exists(path):
        os.remove(path)
    writer = subprocess.Popen([exe, "--writer", out])
    f = None
    deadline = time.time() + 5
    while f is None and time.time() < deadline:
        try:
            f = h5py.File(path, "r", libver="latest", swmr=True)
        except OSError:
            time.sleep(0.02)
    if f is None:
        writer.kill()
        print("FAIL: could not open", path, "with swmr=True")
        return 1
    sizes = []
    with f:
        t = f["t"]
        while True:
            running = writer.poll() is None
            t.refresh()
            n = t.shape[0]
            if running and (not sizes or n > sizes[-1]):
                sizes.append(n)
            if not running:
                break
            time.sleep(0.03)
        t.refresh()
        f["force"].refresh()
        rows = t[()]
        final = f["force"].shape
    errors = []
    if writer.returncode != 0:
        errors.append(f"writer exit status {writer.returncode}")
    if len([s for s in sizes if s > 0]) < 2:
        errors.append(f"saw only the sizes {sizes} while the writer ran")
    if len(rows) != 40 or not np.array_equal(rows, np.arange(40) * 1e-3):
        errors.append(f"final /t has {len(rows)} rows or wrong values")
    if final != (40, 2, 3):
        errors.append(f"final force shape {final}")
    for e in errors:
        print("FAIL", e)
    print(f"test_output_swmr_h5py: sizes seen while writing {sizes}; {'ok' if not errors else 'FAIL'}")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
