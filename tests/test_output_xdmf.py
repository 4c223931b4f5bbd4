#!/usr/bin/python3
"""Every *.xmf below DIR is well-formed XML (xml.etree), its temporal collection has one step
per snapshot, and every HDF DataItem names a dataset that exists (h5py) with the declared
dimensions and number type; topology element counts match the cell arrays.

  tests/test_output_xdmf.py DIR        exit 0 when all holds, 1 otherwise"""
import glob
import os
import sys
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
import lahar_py  # noqa: E402

lahar_py.require("h5py", "numpy")
import h5py  # noqa: E402

KIND = {("Float", "4"): "f4", ("Float", "8"): "f8", ("Int", "4"): "i4", ("Int", "8"): "i8"}


def check_file(xmf, errors):
    base = os.path.dirname(xmf)
    root = ET.parse(xmf).getroot()
    if root.tag != "Xdmf":
        errors.append(f"{xmf}: root is {root.tag}")
        return 0
    temporal = root.find("Domain/Grid")
    steps = temporal.findall("Grid") if temporal is not None else []
    if temporal is None or temporal.get("CollectionType") != "Temporal" or not steps:
        errors.append(f"{xmf}: no temporal collection with steps")
    times = [float(s.find("Time").get("Value")) for s in steps]
    if times != sorted(times):
        errors.append(f"{xmf}: times not increasing")
    files = {}
    nitems = 0
    for item in root.iter("DataItem"):
        if item.get("Format") != "HDF":
            continue
        nitems += 1
        fname, dpath = item.text.strip().split(":", 1)
        path = os.path.join(base, fname)
        if path not in files:
            files[path] = h5py.File(path, "r")
        f = files[path]
        if dpath not in f:
            errors.append(f"{xmf}: {fname}:{dpath} does not exist")
            continue
        ds = f[dpath]
        dims = tuple(int(x) for x in item.get("Dimensions").split())
        if ds.shape != dims:
            errors.append(f"{xmf}: {dpath} has shape {ds.shape}, XDMF says {dims}")
        want = KIND.get((item.get("NumberType"), item.get("Precision")))
        if want is None or ds.dtype.kind + str(ds.dtype.itemsize) != want:
            errors.append(f"{xmf}: {dpath} is {ds.dtype}, XDMF says {item.get('NumberType')}{item.get('Precision')}")
    for topo in root.iter("Topology"):
        n = int(topo.get("NumberOfElements"))
        cells = topo.find("DataItem")
        if cells is not None and int(cells.get("Dimensions").split()[0]) != n:
            errors.append(f"{xmf}: topology says {n} elements, cells have {cells.get('Dimensions')}")
    # one step per snapshot of each file the XDMF refers to
    for path, f in files.items():
        nsnap = len(f["snapshots"]) if "snapshots" in f else 0
        used = {it.text.strip().split(":", 1)[1].split("/")[2] for it in root.iter("DataItem")
                if it.get("Format") == "HDF" and it.text.strip().startswith(os.path.basename(path) + ":/snapshots/")}
        if len(used) != nsnap:
            errors.append(f"{xmf}: refers to {len(used)} snapshots of {os.path.basename(path)}, which has {nsnap}")
    for f in files.values():
        f.close()
    return nitems


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    errors = []
    xmfs = sorted(glob.glob(os.path.join(sys.argv[1], "**", "*.xmf"), recursive=True))
    if not xmfs:
        errors.append(f"no .xmf below {sys.argv[1]}")
    total = 0
    for x in xmfs:
        try:
            total += check_file(x, errors)
        except (ET.ParseError, OSError, KeyError, ValueError, AttributeError) as e:
            errors.append(f"{x}: {type(e).__name__}: {e}")
    for e in errors:
        print("FAIL", e)
    print(f"test_output_xdmf: {len(xmfs)} file(s), {total} HDF data items, {len(errors)} error(s)")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
