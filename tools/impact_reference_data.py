#!/usr/bin/python3
"""Derive the compact experimental series of docs/references-data/ from their public sources.

  tools/impact_reference_data.py [TNL_SPH_GIT_DIR] [--aquagpusph AQUAGPUSPH_GIT_DIR] [-o docs/references-data]

TNL_SPH_GIT_DIR is a clone of https://gitlab.com/tnl-project/tnl-sph (its GitHub mirror
TNL-Project/TNL-SPH), which distributes, under examples/resources/:
  damBreak2D/damBreak2D_experimentalDataLobovsky2014/  Lobovsky et al. 2014, H = 300 mm, digitised
      from the paper's Fig. 16 (water levels, two test runs) and Fig. 18 (pressure, peak event 5);
  damBreak3D/test_case_2_exp_data-experimental_data.csv  SPHERIC Test 2 (Kleefsman et al. 2005,
      MARIN), as distributed by SPHERIC (decimal commas).
AQUAGPUSPH_GIT_DIR is a clone of https://github.com/sanguinariojoe/aquagpusph (CEHINAV, the
experimenters' group), whose example examples/2D/lobovsky_etal_2014/ distributes the repeat spread
of sensor 2 at H = 300 mm: the 2.5 %, 50 % and 97.5 % percentiles of p/(rho g H) at each instant
over the test runs (src/templates/Fig31_Wemmenhove_sensor2_compared_graph.csv; t*, 20 kHz).
The files are read from the repository's HEAD with `git show`. Written (CSV, '#' header lines
citing the source and the derivation):
  lobovsky_2014_pressure.csv   t* = t sqrt(g/H), p/(rho g H) of sensors 1, 2, 2L, 3, 4, linearly
                               resampled to dt* = 0.002 (the source: 0.000286 = 20 kHz)
  lobovsky_2014_levels.csv     t*, h/H of gauges H1 (run ETSIN 01), H2, H3, H4 (runs 01 and 02),
                               the source's own time grid (dt* = 0.019)
  kleefsman_2005_test2.csv     t (s), P1-P8 (Pa), H1-H4 (m), 0-2 s, the source's own samples
                               (~1 kHz), rounded to 0.1 Pa and 0.1 mm
  lobovsky_2014_sensor2_percentiles.csv (from AQUAGPUSPH_GIT_DIR) t*, p/(rho g H) percentiles
                               2.5, 50, 97.5 of sensor 2, linearly resampled to dt* = 0.002
"""
import argparse
import csv
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lahar_py  # noqa: E402

lahar_py.require("numpy")

import numpy as np  # noqa: E402

L2D = "examples/resources/damBreak2D/damBreak2D_experimentalDataLobovsky2014/"
K3D = "examples/resources/damBreak3D/test_case_2_exp_data-experimental_data.csv"
A2D = "examples/2D/lobovsky_etal_2014/src/templates/"  # in AQUAgpusph
# the source's file number of each sensor (its first line names the sensor)
PRESSURE = [("sensor1", 5, "sensor 1"), ("sensor2", 4, "sensor 2"), ("sensor2L", 3, "sensor 2L"),
            ("sensor3", 2, "sensor 3"), ("sensor4", 1, "sensor 4")]
LEVELS = [("H1_run1", "H1_2", "ETSIN 01"), ("H2_run1", "H2_4", "ETSIN 01"), ("H2_run2", "H2_3", "ETSIN 02"),
          ("H3_run1", "H3_4", "ETSIN 01"), ("H3_run2", "H3_3", "ETSIN 02"), ("H4_run1", "H4_5", "ETSIN 01"),
          ("H4_run2", "H4_4", "ETSIN 02")]

LOBOVSKY = ("# Source: L. Lobovsky, E. Botia-Vera, F. Castellana, J. Mas-Soler, A. Souto-Iglesias, Experimental\n"
            "# investigation of dynamic pressure loads during dam break, J. Fluids Struct. 48 (2014) 407-434,\n"
            "# doi:10.1016/j.jfluidstructs.2014.03.009; H = 300 mm, L = 600 mm, tank 1610 mm. Digitised series as\n"
            "# distributed with TNL-SPH (https://gitlab.com/tnl-project/tnl-sph, examples/resources/damBreak2D/\n"
            "# damBreak2D_experimentalDataLobovsky2014/, commit %s).\n")


def git_show(repo, path):
    return subprocess.run(["git", "--git-dir", repo, "show", "HEAD:" + path], check=True, capture_output=True,
                          text=True).stdout


def table(text):
    first = text.splitlines()[0].lstrip("#").strip()
    return first, np.loadtxt(text.splitlines())


def sensor2_percentiles(repo, out):
    """Sensor 2's repeat spread at H = 300 mm (AQUAgpusph's lobovsky_etal_2014 example) on the
    dt* = 0.002 grid of lobovsky_2014_pressure.csv."""
    commit = subprocess.run(["git", "--git-dir", repo, "rev-parse", "HEAD"], check=True, capture_output=True,
                            text=True).stdout.strip()
    text = git_show(repo, A2D + "Fig31_Wemmenhove_sensor2_compared_graph.csv").splitlines()
    if [h.strip('"') for h in text[0].split(",")] != ["p2.5", "median", "p97.5"]:
        sys.exit("%s: unexpected header %s" % (repo, text[0]))
    d = np.loadtxt(text[1:], delimiter=",")
    if not (np.all(d[:, 1] <= d[:, 2]) and np.all(d[:, 2] <= d[:, 3])):
        sys.exit("%s: the percentiles are not ordered" % repo)
    ts = np.arange(0.0, 7.148 + 1e-9, 0.002)
    cols = [ts] + [np.interp(ts, d[:, 0], d[:, k]) for k in (1, 2, 3)]
    for k, name in ((1, "p2.5"), (2, "median"), (3, "p97.5")):
        print("sensor 2 %s: source peak %.3f at t* %.4f, resampled %.3f" % (name, d[:, k].max(), d[d[:, k].argmax(), 0],
                                                                          cols[k].max()))
    with open(os.path.join(out, "lobovsky_2014_sensor2_percentiles.csv"), "w") as fh:
        fh.write("# Source: L. Lobovsky, E. Botia-Vera, F. Castellana, J. Mas-Soler, A. Souto-Iglesias, Experimental\n"
                 "# investigation of dynamic pressure loads during dam break, J. Fluids Struct. 48 (2014) 407-434;\n"
                 "# H = 300 mm, sensor 2 (15 mm above the floor on the downstream wall). The repeat spread as\n"
                 "# distributed with AQUAgpusph (https://github.com/sanguinariojoe/aquagpusph, CEHINAV,\n"
                 "# examples/2D/lobovsky_etal_2014/src/templates/Fig31_Wemmenhove_sensor2_compared_graph.csv, commit\n"
                 "# %s): at each instant the 2.5 %%, 50 %% and 97.5 %% percentiles of p/(rho g H)\n"
                 "# over the test runs, against t* = t sqrt(g/H) (20 kHz; the example plots it against its own run's\n"
                 "# time from the release; the file's name points to the paper's Fig. 31; the rise at t* 2.44-2.49\n"
                 "# matches peak event 5's). Derived by tools/impact_reference_data.py: linear resampling to\n"
                 "# dt* = 0.002 (peaks change by less than 0.5 %%: 97.5 %%: 2.032 -> 2.028).\n" % commit)
        fh.write("t_star,p2_5,median,p97_5\n")
        for row in np.column_stack(cols):
            fh.write("%.3f," % row[0] + ",".join("%.4f" % v for v in row[1:]) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("repo", nargs="?", help="git directory of a TNL-SPH clone (bare or .git)")
    ap.add_argument("--aquagpusph", metavar="GIT_DIR", help="git directory of an AQUAgpusph clone: sensor 2's spread")
    ap.add_argument("-o", "--out", default=os.path.join(os.path.dirname(__file__), "..", "docs", "references-data"))
    a = ap.parse_args()
    if not a.repo and not a.aquagpusph:
        ap.error("give TNL_SPH_GIT_DIR, --aquagpusph GIT_DIR or both")
    if a.aquagpusph:
        sensor2_percentiles(a.aquagpusph, a.out)
    if not a.repo:
        return
    commit = subprocess.run(["git", "--git-dir", a.repo, "rev-parse", "HEAD"], check=True, capture_output=True,
                            text=True).stdout.strip()

    # pressure, Fig. 18 peak event 5: one grid for all sensors
    ts = np.arange(0.0, 7.148 + 1e-9, 0.002)
    cols, names = [ts], ["t_star"]
    for name, k, label in PRESSURE:
        first, d = table(git_show(a.repo, L2D + "pressure/Fig18_peak_event_5_sensors_%d.dat" % k))
        if first != label:
            sys.exit("%s: file %d names '%s', expected '%s'" % (a.repo, k, first, label))
        cols.append(np.interp(ts, d[:, 0], d[:, 1]))
        names.append(name)
        print("%s: source peak %.3f at t* %.4f, resampled %.3f" % (name, d[:, 1].max(), d[d[:, 1].argmax(), 0],
                                                                   cols[-1].max()))
    with open(os.path.join(a.out, "lobovsky_2014_pressure.csv"), "w") as fh:
        fh.write(LOBOVSKY % commit)
        fh.write("# Fig. 18, peak event 5 (one impact event of the H = 300 mm series): pressure on the downstream wall,\n"
                 "# sensors 1-4 on the centre line 3, 15, 30, 80 mm above the floor, 2L beside sensor 2 (same height).\n"
                 "# Columns: t* = t sqrt(g/H) on the source's clock (the event's own time origin), p/(rho g H).\n"
                 "# Derived by tools/impact_reference_data.py: linear resampling of the 20 kHz digitised series\n"
                 "# (dt* = 0.000286) to dt* = 0.002; the peaks change by less than 1 % (sensor 1: 3.044 -> 3.035).\n")
        fh.write(",".join(names) + "\n")
        for row in np.column_stack(cols):
            fh.write("%.3f," % row[0] + ",".join("%.4f" % v for v in row[1:]) + "\n")

    # water levels, Fig. 16: the source's common time grid
    cols, names = None, ["t_star"]
    for name, f, run in LEVELS:
        first, d = table(git_show(a.repo, L2D + "waterLevel/Fig16_WaterLevels_%s.dat" % f))
        if run not in first:
            sys.exit("%s: %s names '%s', expected run %s" % (a.repo, f, first, run))
        if cols is None:
            cols = [d[:, 0]]
        elif not np.allclose(cols[0], d[:, 0]):
            sys.exit("%s: %s has another time grid" % (a.repo, f))
        cols.append(d[:, 1])
        names.append(name)
    with open(os.path.join(a.out, "lobovsky_2014_levels.csv"), "w") as fh:
        fh.write(LOBOVSKY % commit)
        fh.write("# Fig. 16: water levels h/H at gauges H1-H4, x = 0.300, 0.865, 1.114, 1.3625 m from the upstream wall\n"
                 "# (positions of the TNL-SPH damBreak2D example's level sensors), two test runs ETSIN 01 (run1) and\n"
                 "# ETSIN 02 (run2); H1 has run1 only. Columns: t* = t sqrt(g/H) from the gate's release, h/H.\n"
                 "# Derived by tools/impact_reference_data.py: the source's own samples (dt* = 0.019), rounded.\n")
        fh.write(",".join(names) + "\n")
        for row in np.column_stack(cols):
            fh.write("%.4f," % row[0] + ",".join("%.4f" % v for v in row[1:]) + "\n")

    # SPHERIC Test 2, decimal commas
    lines = git_show(a.repo, K3D).splitlines()
    head = [s.strip() for s in lines[0].lstrip("#").split(",")]
    rows = []
    for f in csv.reader(lines[1:]):
        vals = [float(s.replace(",", ".")) for s in f if s.strip() != ""]
        if len(vals) == 13 and vals[0] <= 2.0:
            rows.append(vals)
    d = np.array(rows)
    names = [h.split(" ")[0] for h in head if h]
    if len(names) != 13:
        sys.exit("%s: unexpected header %s" % (K3D, head))
    with open(os.path.join(a.out, "kleefsman_2005_test2.csv"), "w") as fh:
        fh.write("# Source: SPHERIC benchmark Test 2, dam break with an obstacle (MARIN experiment; K.M.T. Kleefsman,\n"
                 "# G. Fekken, A.E.P. Veldman, B. Iwanowski, B. Buchner, A Volume-of-Fluid based simulation method for\n"
                 "# wave impact problems, J. Comput. Phys. 206 (2005) 363-393), https://www.spheric-sph.org/tests/test-02,\n"
                 "# file test_case_2_exp_data (as distributed with TNL-SPH, examples/resources/damBreak3D/, commit\n"
                 "# %s).\n"
                 "# Tank 3.22 x 1 x 1 m, water column 1.228 m long, 0.55 m high; P1-P8 pressure on the obstacle (Pa),\n"
                 "# H1-H4 water heights (m). Derived by tools/impact_reference_data.py: the first 2 s of the\n"
                 "# source's samples (~1 kHz), decimal commas to points, rounded to 0.1 Pa and 0.1 mm.\n" % commit)
        fh.write("t," + ",".join(names[1:]) + "\n")
        for r in d:
            fh.write("%.5f," % r[0] + ",".join("%.1f" % v for v in r[1:9]) + "," +
                     ",".join("%.4f" % v for v in r[9:]) + "\n")
    print("wrote %d + %d + %d rows to %s" % (len(ts), len(cols[0]), len(d), a.out))


if __name__ == "__main__":
    main()
