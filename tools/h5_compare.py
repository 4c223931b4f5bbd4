#!/usr/bin/python3
"""Bitwise comparison of two HDF5 files: every dataset (and with --attrs every attribute) must
exist in both, with the same shape, type and bytes.

  tools/h5_compare.py A.h5 B.h5 [--attrs] [--exclude REGEX ...] [--quiet]

Exit status: 0 identical, 1 different (differences listed on stdout), 2 error (unreadable file).
--exclude skips objects whose path matches the regular expression (e.g. '^/header' or
'case_path'); use it for what legitimately differs between two runs."""
import argparse
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lahar_py  # noqa: E402

lahar_py.require("h5py", "numpy")
import h5py  # noqa: E402
import numpy as np  # noqa: E402


def collect(f, with_attrs):
    """path -> ('dataset', obj) for datasets; path@name -> ('attr', value) for attributes."""
    items = {}

    def visit(name, obj):
        path = "/" + name
        if isinstance(obj, h5py.Dataset):
            items[path] = ("dataset", obj)
        if with_attrs:
            for a in obj.attrs:
                items[path + "@" + a] = ("attr", obj.attrs[a])

    if with_attrs:
        for a in f.attrs:
            items["/@" + a] = ("attr", f.attrs[a])
    f.visititems(visit)
    return items


def as_bytes(value):
    arr = np.asarray(value)
    if arr.dtype.kind == "O":  # variable-length strings: compare their encoded contents
        return repr([x if isinstance(x, bytes) else str(x).encode() for x in arr.ravel()]).encode(), arr.shape, "vlen"
    return arr.tobytes(), arr.shape, arr.dtype.str


def describe(a, b):
    try:
        x, y = np.asarray(a), np.asarray(b)
        if x.shape == y.shape and x.dtype.kind in "fiu" and x.size:
            diff = x != y
            if x.dtype.kind == "f":
                diff &= ~(np.isnan(x) & np.isnan(y))
            idx = np.argwhere(diff)
            first = tuple(int(i) for i in idx[0]) if len(idx) else ()
            maxabs = float(np.max(np.abs(x.astype(np.float64) - y.astype(np.float64))))
            return f"{len(idx)} element(s) differ, first at {first}, max |a-b| = {maxabs:.3g}"
    except (TypeError, ValueError):
        pass
    return "contents differ"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--attrs", action="store_true", help="compare attributes too")
    ap.add_argument("--exclude", action="append", default=[], metavar="REGEX", help="skip matching paths")
    ap.add_argument("--quiet", action="store_true", help="print nothing, only set the exit status")
    args = ap.parse_args()
    excl = [re.compile(r) for r in args.exclude]
    try:
        fa, fb = h5py.File(args.a, "r"), h5py.File(args.b, "r")
    except OSError as e:
        print(f"h5_compare: {e}", file=sys.stderr)
        return 2
    with fa, fb:
        ia, ib = collect(fa, args.attrs), collect(fb, args.attrs)
        diffs = []
        for path in sorted(set(ia) | set(ib)):
            if any(r.search(path) for r in excl):
                continue
            if path not in ia or path not in ib:
                diffs.append(f"{path}: only in {args.a if path in ia else args.b}")
                continue
            va = ia[path][1][()] if ia[path][0] == "dataset" else ia[path][1]
            vb = ib[path][1][()] if ib[path][0] == "dataset" else ib[path][1]
            ba, sa, ta = as_bytes(va)
            bb, sb, tb = as_bytes(vb)
            if sa != sb or ta != tb:
                diffs.append(f"{path}: shape/type {sa} {ta} vs {sb} {tb}")
            elif ba != bb:
                diffs.append(f"{path}: {describe(va, vb)}")
        if not args.quiet:
            for d in diffs:
                print(d)
            n = len([p for p in set(ia) | set(ib) if not any(r.search(p) for r in excl)])
            print(f"h5_compare: {n} object(s) compared, {len(diffs)} differ" if diffs else
                  f"h5_compare: {n} object(s) compared, identical")
        return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main())
